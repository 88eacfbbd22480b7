#!/usr/bin/env bash
# Builds and runs the fuzz targets (tests/fuzz/) for FUZZ_SECONDS each. With clang++ and libFuzzer: a clang
# ASan+libFuzzer build in FUZZ_BUILD_DIR; otherwise the built-in mutation driver from the normal build in
# BUILD_DIR. Seeds are generated (fuzz_seeds) and joined by the regression corpus; findings (crash-*,
# timeout-*, oom-*) land in <build>/fuzz/findings/<target>/, emptied when the target starts (copy a finding
# into tests/fuzz/corpus/<target> to keep it). Prints runs and findings per target and
# exits 1 when anything was found.
set -uo pipefail
: "${BUILD_DIR:=build}" "${FUZZ_BUILD_DIR:=build-fuzz}" "${FUZZ_SECONDS:=60}" "${JOBS:=2}"
targets=(pcd ply depth_png depth_pgm depth_tiff map intrinsics pose)

have_libfuzzer() {
  command -v clang++ >/dev/null 2>&1 || return 1
  local probe; probe=$(mktemp -d)
  echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' > "$probe/p.cpp"
  clang++ -fsanitize=fuzzer "$probe/p.cpp" -o "$probe/p" >/dev/null 2>&1; local ok=$?
  rm -rf "$probe"; return $ok
}

if have_libfuzzer; then
  engine=libfuzzer; dir=$FUZZ_BUILD_DIR
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_DISABLE_FIND_PACKAGE_VTK=TRUE \
        -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
        -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined" \
        -DOCC_IMPROVE_FUZZ_ENGINE=libfuzzer -DOCC_IMPROVE_BUILD_TESTS=ON -DOCC_IMPROVE_BUILD_BENCHMARKS=OFF \
        -DOCC_IMPROVE_BUILD_SAMPLES=OFF >/dev/null || exit 1
else
  engine="built-in mutation driver"; dir=$BUILD_DIR
  $CONFIGURE >/dev/null || exit 1
fi
cmake --build "$dir" -j "$JOBS" --target fuzzers >/dev/null || { echo "fuzz: build failed" >&2; exit 1; }

work="$dir/fuzz"
rm -rf "$work/seeds"
"$dir/tests/fuzz/fuzz_seeds" "$work/seeds" >/dev/null || exit 1
found=0
echo "fuzz: engine $engine, ${FUZZ_SECONDS} s per target"
for t in "${targets[@]}"; do
  rm -rf "$work/findings/$t"  # this run's findings only: a kept one belongs in tests/fuzz/corpus/<target>
  mkdir -p "$work/corpus/$t" "$work/findings/$t"
  log="$work/$t.log"
  # The first folder collects what libFuzzer finds interesting; seeds and the regression corpus only seed.
  "$dir/tests/fuzz/fuzz_$t" -max_total_time="$FUZZ_SECONDS" -timeout=20 -rss_limit_mb=2048 \
      -artifact_prefix="$work/findings/$t/" "$work/corpus/$t" "$work/seeds/$t" "tests/fuzz/corpus/$t" > "$log" 2>&1
  runs=$(grep -oE '(#[0-9]+[[:space:]]+DONE|[0-9]+ runs)' "$log" | tail -1 | grep -oE '[0-9]+' | head -1)
  findings=$(find "$work/findings/$t" -type f | wc -l)
  found=$((found + findings))
  printf '  %-11s %10s runs, %d finding(s)%s\n' "$t" "${runs:-?}" "$findings" \
         "$([ "$findings" -gt 0 ] && echo ": $(ls "$work/findings/$t" | tr '\n' ' ')(log $log)")"
done
[ "$found" -eq 0 ]
