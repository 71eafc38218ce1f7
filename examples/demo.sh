#!/usr/bin/env bash
# Installs what is needed (Debian 12), builds affine_orb in Release and runs the main example on
# Debian opencv-doc's graf1/graf3 pair with its ground-truth homography; writes matches.png and
# rectified.png in the current directory.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/tests/install_deps.sh"
cmake -S "$root" -B "$root/build/release" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$root/build/release" --target affine_orb_match affine_orb_extract
"$root/build/release/examples/affine_orb_match" --out matches.png --rectified rectified.png
