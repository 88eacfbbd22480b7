#!/usr/bin/env bash
# Runs every benchmark built under tests/bench.
set -euo pipefail
build=${1:-build}
shopt -s nullglob
for b in "$build"/tests/bench_*; do
  [ -x "$b" ] || continue
  echo "== $(basename "$b")"
  "$b" --benchmark_counters_tabular=true
done
