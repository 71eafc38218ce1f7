#!/usr/bin/env bash
# The tests of the SIMD code cross-compiled for aarch64 and run under qemu-user: the NEON paths
# against their scalar references, and the same bytes as on x86 where the tests compare with fixed
# data. Needs Debian's g++-aarch64-linux-gnu and qemu-user, and the arm64 packages of OpenCV (core,
# imgproc, imgcodecs, features2d and their dependencies), Eigen and doctest unpacked into a sysroot
# (apt-get download + dpkg -x: nothing of arm64 is installed on the host; the arm64 package lists
# come from `dpkg --add-architecture arm64` and apt-get update). The sysroot and the downloaded
# packages stay in ${AFFINE_ORB_BUILD_ROOT:-build}/aarch64-{sysroot,debs} for the next run.
set -euo pipefail
cd "$(dirname "$0")/.."
root=${AFFINE_ORB_BUILD_ROOT:-build}
jobs=$(nproc)
tests="test_fast test_pyramid test_rbrief test_extractor test_matcher test_brisk test_affine_views"

as_root=()
if [[ $(id -u) -ne 0 ]]; then as_root=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
missing=()
for p in g++-aarch64-linux-gnu qemu-user; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  "${as_root[@]}" apt-get update -q
  "${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

mkdir -p "$root"
sysroot=$(realpath "$root")/aarch64-sysroot
if [[ ! -f $sysroot/.complete ]]; then
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    "${as_root[@]}" dpkg --add-architecture arm64
    "${as_root[@]}" apt-get update -q
  fi
  debs="$root/aarch64-debs"
  mkdir -p "$debs"
  # The arm64 packages the OpenCV modules depend on, recursively (Depends and Pre-Depends only).
  mapfile -t packages < <(apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks \
      --no-replaces --no-enhances libopencv-imgcodecs-dev:arm64 libopencv-features2d-dev:arm64 \
      libopencv-calib3d-dev:arm64 |
    grep -E '^[a-z0-9][^ ]*:arm64$' | sort -u)
  (cd "$debs" && apt-get download -q "${packages[@]}" libeigen3-dev doctest-dev)
  rm -rf "$sysroot" && mkdir -p "$sysroot"
  for deb in "$debs"/*.deb; do dpkg -x "$deb" "$sysroot"; done
  # What update-alternatives would link: the reference BLAS and LAPACK that OpenCV loads.
  for lib in blas/libblas.so.3 lapack/liblapack.so.3; do
    ln -sf "$lib" "$sysroot/usr/lib/aarch64-linux-gnu/$(basename "$lib")"
  done
  touch "$sysroot/.complete"
fi

cmake -S . -B "$root/aarch64" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_TOOLCHAIN_FILE="$PWD/cmake/aarch64-linux-gnu.cmake" -DAFFINE_ORB_AARCH64_SYSROOT="$sysroot" \
  -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF -DAFFINE_ORB_BUILD_ADAPTERS=OFF \
  -DAFFINE_ORB_BUILD_PYTHON=OFF
cmake --build "$root/aarch64" -j "$jobs" --target $tests
# Each program's cases that read the evaluation data run as <program>_data (tests/CMakeLists.txt).
ctest --test-dir "$root/aarch64" --output-on-failure -j "$jobs" -R "^(${tests// /|})(_data)?\$"
