#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run calls exactly this script):
#   1. installs the Debian 12 packages it needs (when run as root and they are missing);
#   2. Release build of the library, tests, examples and benchmarks; ctest (which includes the
#      install + find_package(affine_orb) consumer check);
#   3. the test suite again under AddressSanitizer + UndefinedBehaviorSanitizer (all but the
#      memory-flatness test, which ASan's quarantine would defeat);
#   4. the threaded tests under ThreadSanitizer (clang);
#   5. the libFuzzer target for a bounded time (AFFINE_ORB_FUZZ_SECONDS, default 60) from the
#      checked-in seed corpus (clang, ASan + UBSan);
#   6. on a CPU with AVX2, the tests of the SIMD code again with -march=native
#      (AFFINE_ORB_NATIVE), so that the AVX2 paths, which the default build does not compile, are
#      checked against their scalar references too.
# Build trees go to ${AFFINE_ORB_BUILD_ROOT:-build}/{release,asan,tsan,fuzz,native}.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tests/install_deps.sh

root=${AFFINE_ORB_BUILD_ROOT:-build}
jobs=$(nproc)

echo "== Release build and tests"
cmake -S . -B "$root/release" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$root/release" -j "$jobs"
ctest --test-dir "$root/release" --output-on-failure -j "$jobs"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer"
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
cmake -S . -B "$root/asan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF \
  -DCMAKE_CXX_FLAGS="$sanitize" -DCMAKE_EXE_LINKER_FLAGS="$sanitize"
cmake --build "$root/asan" -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$root/asan" --output-on-failure -j "$jobs" -E "install_consumer|test_long_run"

echo "== ThreadSanitizer (threaded tests)"
CC=clang CXX=clang++ cmake -S . -B "$root/tsan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF \
  -DCMAKE_CXX_FLAGS="-fsanitize=thread" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread"
cmake --build "$root/tsan" -j "$jobs" --target test_concurrency test_affine_views
TSAN_OPTIONS="suppressions=$PWD/tests/tsan.supp halt_on_error=1" \
  ctest --test-dir "$root/tsan" --output-on-failure -R "test_concurrency|test_affine_views"

echo "== libFuzzer (${AFFINE_ORB_FUZZ_SECONDS:-60} s)"
CC=clang CXX=clang++ cmake -S . -B "$root/fuzz" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF \
  -DAFFINE_ORB_BUILD_FUZZERS=ON
cmake --build "$root/fuzz" -j "$jobs" --target fuzz_extract
corpus="$root/fuzz/corpus"
rm -rf "$corpus" && mkdir -p "$corpus"
set +e
"$root/fuzz/tests/fuzz_extract" -max_total_time="${AFFINE_ORB_FUZZ_SECONDS:-60}" -timeout=30 -rss_limit_mb=4096 \
  -print_final_stats=1 -artifact_prefix="$root/fuzz/" "$corpus" tests/fuzz/corpus > "$root/fuzz/fuzz.log" 2>&1
status=$?
set -e
grep -E "^(Done|stat::number_of_executed_units|stat::new_units_added)" "$root/fuzz/fuzz.log" || true
if [[ $status -ne 0 ]]; then
  tail -n 80 "$root/fuzz/fuzz.log"
  echo "the fuzzer found a problem (exit $status); the input is in $root/fuzz/" >&2
  exit 1
fi

if grep -qw avx2 /proc/cpuinfo; then
  echo "== -march=native (AVX2 paths)"
  simd_tests="test_fast|test_distribution|test_rbrief|test_extractor|test_matcher|test_brisk"
  cmake -S . -B "$root/native" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFFINE_ORB_NATIVE=ON \
    -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF
  cmake --build "$root/native" -j "$jobs" --target ${simd_tests//|/ }
  ctest --test-dir "$root/native" --output-on-failure -j "$jobs" -R "$simd_tests"
else
  echo "== -march=native skipped: this CPU has no AVX2"
fi
echo "all stages passed"
