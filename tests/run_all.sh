#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run calls exactly this script):
#   1. installs the Debian 12 packages it needs (when run as root and they are missing);
#   2. Release build of the library, tests, examples, benchmarks and the Python module; ctest
#      (which includes the install + find_package(affine_orb)/pkg-config consumer check and the module's
#      pytest suite), after tests/check_data.sh has checked the evaluation data, so that the tests
#      labelled "data" run here instead of being skipped;
#   3. the Debian packages (tests/package_check.sh): built with cpack, installed with apt-get,
#      used by a C++ consumer (find_package and pkg-config) and by /usr/bin/python3, removed again
#      (skipped when not root and sudo needs a password);
#   4. the test suite again under AddressSanitizer + UndefinedBehaviorSanitizer (all but the
#      memory-flatness test, which ASan's quarantine would defeat);
#   5. the threaded tests under ThreadSanitizer (clang);
#   6. the libFuzzer targets, each for a bounded time from its checked-in seed corpus (clang, ASan +
#      UBSan), with their executions per second;
#   7. on a CPU with AVX2, test_matcher again with -march=native (AFFINE_ORB_NATIVE), so that the
#      paths chosen at compile time there (empty AVX2 regions, POPCNT in hamming_distance) are
#      checked against the naive search too (the default build chooses the AVX2 kernels at run
#      time, and its tests check them on such a CPU);
#   8. the tests of the SIMD code cross-compiled for aarch64 and run under qemu-user
#      (tests/cross_aarch64.sh), so that the NEON paths are checked against their scalar
#      references and the fixed data.
# Build trees go to ${AFFINE_ORB_BUILD_ROOT:-build}/{release,package,asan,tsan,fuzz,native,aarch64}.
set -euo pipefail
cd "$(dirname "$0")/.."

bash tests/install_deps.sh

root=${AFFINE_ORB_BUILD_ROOT:-build}
jobs=$(nproc)
# Each stage's header gives the seconds since the start, so a CI log shows where the time goes.
stage() { echo "== $* (at ${SECONDS} s)"; }

stage "Release build and tests"
bash tests/check_data.sh
cmake -S . -B "$root/release" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$root/release" -j "$jobs"
ctest --test-dir "$root/release" --output-on-failure -j "$jobs"

stage "Debian packages"
bash tests/package_check.sh

stage "AddressSanitizer + UndefinedBehaviorSanitizer"
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
# -O1 with line tables only: half the compile time of -O2 -g for a little more run time of the tests
# (test_extractor and test_two_view: 155 against 289 s CPU to build, 9.6 against 8.1 s to run),
# and ASan's reports still name file and line.
cmake -S . -B "$root/asan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_PYTHON=OFF \
  -DCMAKE_CXX_FLAGS="$sanitize" -DCMAKE_EXE_LINKER_FLAGS="$sanitize"
cmake --build "$root/asan" -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir "$root/asan" --output-on-failure -j "$jobs" -E "install_consumer|test_long_run"

stage "ThreadSanitizer (threaded tests)"
CC=clang CXX=clang++ cmake -S . -B "$root/tsan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF \
  -DAFFINE_ORB_BUILD_PYTHON=OFF -DCMAKE_CXX_FLAGS="-fsanitize=thread" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread"
cmake --build "$root/tsan" -j "$jobs" --target test_concurrency test_affine_views test_views_on_demand
TSAN_OPTIONS="suppressions=$PWD/tests/tsan.supp halt_on_error=1" \
  ctest --test-dir "$root/tsan" --output-on-failure -R "test_concurrency|test_affine_views|test_views_on_demand"

stage "libFuzzer"
CC=clang CXX=clang++ cmake -S . -B "$root/fuzz" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF \
  -DAFFINE_ORB_BUILD_PYTHON=OFF -DAFFINE_ORB_BUILD_FUZZERS=ON
fuzzers="fuzz_extract fuzz_fast fuzz_describe fuzz_matcher fuzz_model_selection fuzz_readers fuzz_two_view"
cmake --build "$root/fuzz" -j "$jobs" --target $fuzzers
# Each target runs from its checked-in seed corpus for a bounded time (the whole extraction
# AFFINE_ORB_FUZZ_SECONDS, default 60; the stage targets AFFINE_ORB_FUZZ_STAGE_SECONDS, default
# 30) and reports its executions per second. A finding stops CI; its input is kept in
# $root/fuzz/ and becomes a regression test.
for fuzzer in $fuzzers; do
  seconds=${AFFINE_ORB_FUZZ_STAGE_SECONDS:-30}
  [[ $fuzzer == fuzz_extract ]] && seconds=${AFFINE_ORB_FUZZ_SECONDS:-60}
  corpus="$root/fuzz/corpus/$fuzzer"
  rm -rf "$corpus" && mkdir -p "$corpus"
  log="$root/fuzz/$fuzzer.log"
  set +e
  "$root/fuzz/tests/$fuzzer" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=4096 -print_final_stats=1 \
    -artifact_prefix="$root/fuzz/$fuzzer-" "$corpus" "tests/fuzz/corpus/$fuzzer" > "$log" 2>&1
  status=$?
  set -e
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  time=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log")
  echo "$fuzzer: ${runs:-0} inputs in ${time:-?} s ($(( ${runs:-0} / ${time:-1} )) per second), $(sed -n 's/^stat::new_units_added: *//p' "$log") new coverage units"
  if [[ $status -ne 0 ]]; then
    tail -n 80 "$log"
    echo "$fuzzer found a problem (exit $status); the input is in $root/fuzz/" >&2
    exit 1
  fi
done

if grep -qw avx2 /proc/cpuinfo; then
  stage "-march=native (the matcher's compile-time AVX2 and POPCNT paths)"
  cmake -S . -B "$root/native" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFFINE_ORB_NATIVE=ON \
    -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF \
    -DAFFINE_ORB_BUILD_PYTHON=OFF
  cmake --build "$root/native" -j "$jobs" --target test_matcher
  ctest --test-dir "$root/native" --output-on-failure -j "$jobs" -R test_matcher
else
  stage "-march=native skipped: this CPU has no AVX2"
fi

stage "aarch64 under qemu-user (SIMD tests)"
bash tests/cross_aarch64.sh
echo "all stages passed in ${SECONDS} s"
