#!/bin/bash
# walk.sh NAME=SOURCE... -- the walk along a wall (adapters/tests/walk.hpp) for each extractor, on the
# Oxford walls graf, boat, bikes and trees (img1): keypoints found again one frame and 20 frames on,
# within 40 px of the border, cells occupied, and the share of the first extractor's keypoints (every
# frame's) that each other one also picks: same octave, within one level pixel; all octaves and
# octave 0. One Markdown table, the extractors side by side.
# SOURCE: as extractor_source.sh says (a fork's own extractor, the adapter installed in a fork, or an
# affine_orb checkout's adapter).
# Environment: DATA (default ../shared/data beside this project), CXX (default g++).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
# shellcheck source-path=SCRIPTDIR
. "$HERE/extractor_source.sh"
PROJECT=$(cd "$HERE/../.." && pwd)
DATA=${DATA:-$PROJECT/../shared/data}
[ $# -ge 1 ] || { sed -n '2,/^# Environment/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
WALLS=()
for w in graf boat bikes trees; do WALLS+=("$DATA/oxford/$w/img1.png"); done
BIN=$(mktemp -d); trap 'rm -rf "$BIN"' EXIT
for arg in "$@"; do extractor_check "${arg#*=}"; done  # every source before the table starts
first=${1%%=*}
echo "| extractor | wall | keypoints | found again 1 frame on | 20 frames on | within 40 px of the border | cells occupied | shared with $first | octave 0 |"
echo '|---|---|---|---|---|---|---|---|---|'
mode=--save
for arg in "$@"; do
  name=${arg%%=*}
  extractor_compile "${arg#*=}" "$HERE/walk.cpp" "$BIN/$name" -I"$PROJECT/adapters/tests"
  "$BIN/$name" "$name" $mode "$BIN/first" "${WALLS[@]}"
  mode=--shared
done
