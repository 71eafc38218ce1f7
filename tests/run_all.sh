#!/usr/bin/env bash
# The whole test suite, as CI runs it (.ci/run calls exactly this script):
#   1. installs the Debian 12 packages it needs (when run as root and they are missing);
#   2. Release build of the library, tests, examples and benchmarks; ctest (which includes the
#      install + find_package(affine_orb) consumer check);
#   3. the test suite again under AddressSanitizer + UndefinedBehaviorSanitizer.
# Build trees go to ${AFFINE_ORB_BUILD_ROOT:-build}/{release,asan}.
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
  ctest --test-dir "$root/asan" --output-on-failure -j "$jobs" -E install_consumer
