#!/bin/bash
# walk.sh NAME=SOURCE... -- the walk along a wall (adapters/tests/walk.hpp) for each extractor, on the
# Oxford walls graf, boat, bikes and trees (img1): keypoints found again one frame and 20 frames on,
# within 40 px of the border, cells occupied, and the share of the first extractor's keypoints (every
# frame's) that each other one also picks: same octave, within one level pixel; all octaves and
# octave 0. One Markdown table, the extractors side by side.
# SOURCE is either
#   an ORB-SLAM2 or ORB-SLAM3 tree: its own src/ORBextractor.cc (stock), or the adapter that
#     adapters/orbslam*/install.sh put there (then with the affine_orb checkout its CMakeLists.txt names);
#   an affine_orb checkout (e.g. `git archive REV include adapters | tar -x -C DIR`): its ORB-SLAM2 adapter.
# Environment: DATA (default ../shared/data beside this project), CXX (default g++).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
PROJECT=$(cd "$HERE/../.." && pwd)
DATA=${DATA:-$PROJECT/../shared/data}
[ $# -ge 1 ] || { sed -n '2,/^# Environment/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
WALLS=()
for w in graf boat bikes trees; do WALLS+=("$DATA/oxford/$w/img1.png"); done
OPENCV=$(pkg-config --cflags --libs opencv4)
BIN=$(mktemp -d); trap 'rm -rf "$BIN"' EXIT
for arg in "$@"; do  # every source checked before the table starts
  src=${arg#*=}
  [ -f "$src/adapters/orbslam2/ORBextractor.cc" ] || [ -f "$src/src/ORBextractor.cc" ] ||
    { echo "$src: neither an ORB-SLAM tree nor an affine_orb checkout" >&2; exit 2; }
done
first=${1%%=*}
echo "| extractor | wall | keypoints | found again 1 frame on | 20 frames on | within 40 px of the border | cells occupied | shared with $first | octave 0 |"
echo '|---|---|---|---|---|---|---|---|---|'
mode=--save
for arg in "$@"; do
  name=${arg%%=*}; src=$(readlink -f "${arg#*=}")
  flags=(-O2 -std=c++17 -w -I"$PROJECT/adapters/tests")
  if [ -f "$src/adapters/orbslam2/ORBextractor.cc" ]; then  # an affine_orb checkout
    cc=$src/adapters/orbslam2/ORBextractor.cc
    flags+=(-I"$src/adapters/orbslam2" -I"$src/adapters/common" -I"$src/include" -I/usr/include/eigen3)
  else  # a fork
    cc=$src/src/ORBextractor.cc
    flags+=(-I"$src/include")
    grep -q 'namespace ORB_SLAM3' "$src/include/ORBextractor.h" && flags+=(-DWALK_ORBSLAM3)
    affine=$(sed -n 's/^set(AFFINE_ORB_DIR "\(.*\)")$/\1/p' "$src/CMakeLists.txt")
    [ -n "$affine" ] && flags+=(-I"$affine/include" -I"$affine/adapters/common" -I/usr/include/eigen3)
  fi
  # shellcheck disable=SC2086  # OPENCV holds several words
  ${CXX:-g++} "${flags[@]}" "$HERE/walk.cpp" "$cc" -o "$BIN/$name" $OPENCV
  "$BIN/$name" "$name" $mode "$BIN/first" "${WALLS[@]}"
  mode=--shared
done
