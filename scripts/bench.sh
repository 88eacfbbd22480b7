#!/usr/bin/env bash
# Runs every benchmark built under tests/bench: scripts/bench.sh [build-dir] [benchmark flags...]
# e.g. scripts/bench.sh build --benchmark_filter=InsertSample. Real data is found through
# OCC_IMPROVE_DATA_DIR (else the folder configured at build time); benchmarks without it are skipped.
set -euo pipefail
build=${1:-build}
shift || true
shopt -s nullglob
found=0
for b in "$build"/tests/bench_*; do
  [ -x "$b" ] || continue
  found=1
  echo "== $(basename "$b")"
  "$b" --benchmark_counters_tabular=true "$@"
done
if [ "$found" -eq 0 ]; then
  echo "bench: no benchmark executables in $build/tests (build the 'benchmarks' target first)" >&2
  exit 1
fi
