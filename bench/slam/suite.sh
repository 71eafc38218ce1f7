#!/bin/bash
# suite.sh -- the regression suite of the drop-in, in ORB-SLAM2 or ORB-SLAM3: stock against the
# adapter's defaults (A0) and its recovery default (R3) on many seeds of every rendered sequence,
# RGB-D and monocular, plus mono_kitti on KITTI 00; prints one table per sequence type and every
# sequence where an adapter configuration is worse than stock beyond the run-to-run range
# (slam_tables.py suite), then the monocular maps judged on the frames every map covers, with their
# scale drift (slam_tables.py span).
#
# usage: suite.sh --stock TREE --adapter TREE [options]
#   --stock TREE       the fork built with rgbd_tum, mono_tum and mono_kitti: ORB-SLAM2 by
#                      ../shared/slam/build_orbslam2.sh (TARGETS="rgbd_tum mono_tum mono_kitti"), or
#                      ORB-SLAM3 by bench/slam/build_orbslam3.sh (told as install.sh tells them)
#   --adapter TREE     a copy with the adapter installed by adapters/orbslam2/install.sh --recovery
#                      (adapters/orbslam3/ for ORB-SLAM3) and rebuilt; A0 runs it with
#                      AFFINE_ORB_RECOVERY_IMAGE_FEATURES=1 (the recovery extraction then equals the
#                      normal one), R3 with the recovery defaults
#   --vocab FILE       vocabulary, text format (default /tmp/orbslam2/voc.txt)
#   --synth DIR        renders: DIR/SEQUENCE_sSEED/ (default /tmp/synth); missing ones are rendered
#   --runs DIR         runs (default /tmp/slam_suite; KITTI 00 in DIR/kitti)
#   --seeds 'N ...'    seeds of every rendered sequence (default: 1 to 10)
#   --sequences '...'  (default 'oblique fast shake revisit_sweep'); revisit_sweep_A is the head-on
#                      wall of revisit_sweep alone (its first 250 frames, before the cut: the
#                      keyframes a map has when tracking is lost there; 0.55x the rendering)
#   --modes '...'      (default 'rgbd mono')
#   --repeats N        runs per seed, mode and configuration (default 2; the seeds give the spread)
#   --kitti-repeats N  mono_kitti runs per configuration on KITTI 00 (default 6; 0 = none)
#   --jobs N           render processes (default 2)
#   --tables-only      print the tables of the runs already in --runs
#   --confs '...'      the configurations the tables show, stock first (default 'S A0 R3'; other names
#                      come from runs added with ../shared/slam/run.sh into the same --runs)
# ORB-SLAM3 reads the renders' camera.yaml only with Camera.type: the runs read the renders through
# RUNS/sequences/, links to their files beside a camera.yaml that adds `Camera.type: "PinHole"`.
# Environment: SLAM_HARNESS (default ../shared/slam beside this project), KITTI_DATA as kitti_runs.sh.
# Every step can be repeated: renders are reused, runs are redone (run.sh --first to add more).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
HARNESS=${SLAM_HARNESS:-$HERE/../../../shared/slam}
STOCK=; ADAPTER=; VOCAB=/tmp/orbslam2/voc.txt; SYNTH=/tmp/synth; RUNS=/tmp/slam_suite
SEEDS=$(seq -s ' ' 1 10); SEQUENCES='oblique fast shake revisit_sweep'; MODES='rgbd mono'
REPEATS=2; KITTI_REPEATS=6; JOBS=2; TABLES_ONLY=0; CONFS='S A0 R3'
FRAMES_A=250  # revisit_sweep's part A, the head-on wall (synth_rgbd.py: frames 0-249, then the cut)
usage() { sed -n '/^# usage/,/^# Every step/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }
while [ $# -gt 0 ]; do
  case $1 in
    --stock) STOCK=$2; shift 2;;
    --adapter) ADAPTER=$2; shift 2;;
    --vocab) VOCAB=$2; shift 2;;
    --synth) SYNTH=$2; shift 2;;
    --runs) RUNS=$2; shift 2;;
    --seeds) SEEDS=$2; shift 2;;
    --sequences) SEQUENCES=$2; shift 2;;
    --modes) MODES=$2; shift 2;;
    --repeats) REPEATS=$2; shift 2;;
    --kitti-repeats) KITTI_REPEATS=$2; shift 2;;
    --jobs) JOBS=$2; shift 2;;
    --tables-only) TABLES_ONLY=1; shift;;
    --confs) CONFS=$2; shift 2;;
    *) usage;;
  esac
done
tables() {  # the configurations of CONFS that have runs, stock first
  local present=()
  for c in $CONFS; do [ -d "$RUNS/$c" ] && present+=("$c"); done
  /usr/bin/python3 "$HARNESS/analyze.py" --runs "$RUNS" --seqs "$SYNTH" --confs "${present[*]}" > /dev/null
  KITTI=${KITTI_DATA:-$HERE/../../../shared/data/kitti00}
  [ -d "$RUNS/kitti" ] && /usr/bin/python3 "$HARNESS/kitti_to_tum.py" "$KITTI/poses.txt" "$KITTI/times.txt" \
    "$RUNS/kitti/groundtruth.txt" > /dev/null
  /usr/bin/python3 "$HERE/slam_tables.py" suite "$RUNS" "$SYNTH" "${present[@]}"
  echo; echo "Monocular maps where every configuration's map exists (slam_tables.py span):"; echo
  /usr/bin/python3 "$HERE/slam_tables.py" span "$RUNS" "$SYNTH" "${present[@]}"
}
if [ "$TABLES_ONLY" = 1 ]; then tables; exit 0; fi
if [ -z "$STOCK" ] || [ -z "$ADAPTER" ]; then usage; fi
fork() {  # orbslam2, orbslam3 or None: the tree as adapters/common/install_adapter.py reads it
  /usr/bin/python3 -B -c 'import pathlib, sys; sys.path.insert(0, sys.argv[1]); import install_adapter
print(install_adapter.fork_kind(pathlib.Path(sys.argv[2])))' "$HERE/../../adapters/common" "$1"
}
FORK=$(fork "$STOCK")
[ "$FORK" != None ] || { echo "--stock $STOCK: not an ORB-SLAM2 or ORB-SLAM3 tree" >&2; exit 2; }
[ "$(fork "$ADAPTER")" = "$FORK" ] ||
  { echo "--stock $STOCK and --adapter $ADAPTER are not the same fork" >&2; exit 2; }
grep -q "SetRecovering" "$ADAPTER/src/Tracking.cc" ||
  { echo "$ADAPTER: no recovery lines in src/Tracking.cc (adapters/$FORK/install.sh --recovery)" >&2; exit 2; }

# The renderer and the tables (../shared/slam/README.md: synth_rgbd.py needs scipy besides numpy and
# OpenCV's Python module).
# shellcheck source=bench/slam/debian_packages.sh
. "$HERE/debian_packages.sh"
install_missing python3-numpy python3-scipy python3-opencv

names=()  # seeds outermost, then the sequences
for seed in $SEEDS; do
  for s in $SEQUENCES; do
    d=$SYNTH/${s}_s$seed; names+=("${s}_s$seed")
    [ -f "$d/render_done.txt" ] && continue
    if [ "$s" = revisit_sweep_A ]; then
      /usr/bin/python3 "$HARNESS/synth_rgbd.py" --sequence revisit_sweep --last $((FRAMES_A - 1)) --seed "$seed" \
        --out "$d" --jobs "$JOBS" > "$d.log" 2>&1
      for f in associations.txt rgb.txt depth.txt; do  # the frames rendered, header lines kept
        awk -v n="$FRAMES_A" '/^#/ {print; next} ++k <= n' "$d/$f" > "$d/$f.part" && mv "$d/$f.part" "$d/$f"
      done
    else
      /usr/bin/python3 "$HARNESS/synth_rgbd.py" --sequence "$s" --seed "$seed" --out "$d" --jobs "$JOBS" > "$d.log" 2>&1
    fi
    date -Is > "$d/render_done.txt"
  done
done
RUN_SEQS=$SYNTH
if [ "$FORK" = orbslam3 ]; then
  RUN_SEQS=$RUNS/sequences
  for name in "${names[@]}"; do
    rm -rf "${RUN_SEQS:?}/$name"; mkdir -p "$RUN_SEQS/$name"
    for f in "$SYNTH/$name"/*; do
      [ "${f##*/}" = camera.yaml ] || ln -s "$(readlink -f "$f")" "$RUN_SEQS/$name/"
    done
    { cat "$SYNTH/$name/camera.yaml"; echo; echo 'Camera.type: "PinHole"'; } > "$RUN_SEQS/$name/camera.yaml"
  done
fi
# In the order of names (run.sh interleaves the configurations within each sequence and run).
for name in "${names[@]}"; do
  "$HARNESS/run.sh" --stock "$STOCK" --affine "$ADAPTER" --vocab "$VOCAB" --seqs "$RUN_SEQS" --runs "$RUNS" \
    --conf S=stock --conf 'A0=affine AFFINE_ORB_RECOVERY_IMAGE_FEATURES=1' --conf R3=affine \
    --modes "$MODES" --repeats "$REPEATS" "$name"
done
if [ "$KITTI_REPEATS" -gt 0 ]; then
  VOCAB=$VOCAB "$HERE/kitti_runs.sh" "$RUNS/kitti" 1 "$KITTI_REPEATS" "S=$STOCK" \
    "A0=$ADAPTER AFFINE_ORB_RECOVERY_IMAGE_FEATURES=1" "R3=$ADAPTER"
fi
tables
