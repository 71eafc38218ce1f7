#!/bin/bash
# init_chain.sh NAME=SOURCE... -- SEQUENCE... -- what ORB-SLAM's monocular initialisation gets from
# each extractor on each sequence, without running SLAM (init_chain.cpp says how it matches): octave-0
# keypoints per frame, matches one frame on, how many frames a reference keeps ORB-SLAM's 100 matches
# (every frame as the reference), and the references of ORB-SLAM's own chain from frame 0. One
# Markdown table, the extractors side by side on each sequence.
# SOURCE: as extractor_source.sh says (a fork's own extractor, the adapter installed in a fork, or an
# affine_orb checkout's adapter). SEQUENCE: a TUM-layout folder with rgb.txt and camera.yaml (the
# renders of ../shared/slam/synth_rgbd.py).
# Environment: CXX (default g++).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
# shellcheck source-path=SCRIPTDIR
. "$HERE/extractor_source.sh"
usage() { sed -n '2,/^# Environment/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
SOURCES=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do SOURCES+=("$1"); shift; done
if [ $# -lt 2 ] || [ ${#SOURCES[@]} -eq 0 ]; then usage; fi
shift
for arg in "${SOURCES[@]}"; do extractor_check "${arg#*=}"; done
for s in "$@"; do
  if [ ! -f "$s/rgb.txt" ] || [ ! -f "$s/camera.yaml" ]; then echo "$s: no rgb.txt and camera.yaml" >&2; exit 2; fi
done
BIN=$(mktemp -d); trap 'rm -rf "$BIN"' EXIT
for arg in "${SOURCES[@]}"; do extractor_compile "${arg#*=}" "$HERE/init_chain.cpp" "$BIN/${arg%%=*}"; done
echo '| extractor | sequence | octave-0 keypoints | matches 1 frame on | frames a reference keeps 100 matches | references keeping them 10+ frames | chain from frame 0: references | of them 10+ frames |'
echo '|---|---|---|---|---|---|---|---|'
for s in "$@"; do
  for arg in "${SOURCES[@]}"; do "$BIN/${arg%%=*}" "${arg%%=*}" "$s"; done
done
