#!/usr/bin/env bash
# The main job on the built-in sample.
set -euo pipefail
build=${1:-build}
"$build/samples/example_insert_sample"
