#!/usr/bin/env bash
# Installs the Debian 12 packages affine_orb's build, tests, examples and benchmarks need, when
# they are missing. Runs apt-get as root, or through sudo when not root.
set -euo pipefail
packages=(cmake ninja-build g++ clang libclang-rt-14-dev pkg-config libopencv-dev libeigen3-dev doctest-dev opencv-doc
          pybind11-dev python3-dev python3-numpy python3-opencv python3-pytest
          libbenchmark-dev  # bench_stages (Google Benchmark)
          libyaml-cpp-dev nlohmann-json3-dev libspdlog-dev  # stella_vslam's stock extractor (tests/stock)
          dpkg-dev file)  # the last two for cpack's Debian packages (dpkg-shlibdeps, file)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
((${#missing[@]})) || exit 0
echo "installing: ${missing[*]}"
as_root=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  as_root=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -q
"${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
