#!/bin/bash
# stella_suite.sh -- the regression suite of the drop-in in stella_vslam: stella's own extractor (S)
# against the adapter's default, stella's own keypoints and bits (A0), its 18 affine views (V,
# AFFINE_ORB_MAX_TILT=2.83) and, with --recovery, its recovery mode (R), on many seeds of every rendered sequence, RGB-D and monocular, plus
# run_kitti_slam on KITTI 00; prints one table per sequence type and every sequence where an adapter
# configuration is worse than stock beyond the run-to-run range (slam_tables.py suite). The sibling
# of suite.sh (ORB-SLAM2/3); the runs have the layout of ../shared/slam/run.sh, so that analyze.py
# and slam_tables.py read them unchanged.
#
# usage: stella_suite.sh --stock PREFIX/stock --adapter PREFIX/affine [options]
#   --stock TREE       the stock tree build_stella.sh makes: TREE/stella_vslam (the source, its
#                      example/ configs) and TREE/build/examples/run_{tum_rgbd,image,kitti}_slam
#   --adapter TREE     the tree of build_stella.sh --affine PROJECT: the same with the adapter
#                      installed (adapters/stella_vslam/install.sh: TREE/stella_vslam/.affine_orb_backup/
#                      holds stella's own orb_extractor.cc); any other tree is refused
#   --recovery TREE    adds configuration R: a tree with the adapter installed by install.sh --recovery
#                      (its system.cc reports lost tracking) and rebuilt (build_stella.sh --tree NAME)
#   --run '...'        the configurations to run (default: all given, S A0 V and R with --recovery)
#   --vocab FILE       FBoW vocabulary (default: STOCK/../vocab/orb_k10_L5.fbow, where build_stella.sh
#                      writes it)
#   --synth DIR        renders: DIR/SEQUENCE_sSEED/ (default /tmp/synth); this script renders nothing:
#                      it waits for each render's render_done.txt (up to WAIT_RENDER s, default 3600)
#   --runs DIR         runs (default /tmp/stella_suite; KITTI 00 in DIR/kitti)
#   --seeds 'N ...'    seeds of every rendered sequence (default: 1 to 5)
#   --sequences '...'  (default 'revisit_sweep oblique fast shake')
#   --modes '...'      (default 'rgbd mono')
#   --repeats N        runs per seed, mode and configuration (default 2; the seeds give the spread)
#   --first I          index of the first run (default 1; e.g. 3 adds runs 3.. to earlier ones), KITTI too
#   --kitti-repeats N  run_kitti_slam runs per configuration on KITTI 00 (default 6; 0 = none)
#   --tables-only      print the tables of the runs already in --runs
#   --confs '...'      the configurations the tables show, stock first (default 'S A0 V R')
# Per render and mode, RUNS/stella_configs/SEQUENCE_MODE.yaml is written from the render's camera.yaml
# (ORB-SLAM keys: intrinsics, distortion, fps, size, Camera.bf, ThDepth, DepthMapFactor, Camera.RGB,
# the ORBextractor scale, levels and FAST thresholds), with the Tracking and Mapping sections of
# stella's own example/tum_rgbd/TUM_RGBD_{rgbd,mono}_1.yaml and Preprocessing min_size 800 as there.
# RGB-D runs run_tum_rgbd_slam on the render, monocular run_image_slam on RENDER/rgb with
# --start-timestamp of its first frame (the PNGs are consecutive frames at Camera.fps, so stella's
# timestamps are the render's), both with --auto-term --viewer none --eval-log-dir and without
# --no-sleep: paced in real time, so that a faster extractor gets no less mapping time per frame.
# One run at a time: seeds outermost, then sequence, repeat, mode, and the configurations innermost.
# A run writes RUNS/CONF/SEQUENCE/MODE_I/ as run.sh does (cmd.txt, log.txt with each line prefixed by
# seconds since the start, time.txt from /usr/bin/time -v, rc.txt, start/end.txt, load_start/end.txt;
# RUNS/CONF/config.txt), stella's frame_trajectory.txt as CameraTrajectory.txt (RGB-D) and its
# keyframe_trajectory.txt as KeyFrameTrajectory.txt. analyze.py counts ORB-SLAM2's words in log.txt
# (`New Map created`, `System Reseting`, `Loop detected`, ...) and counts a run without `Saving` as a
# crash; stella says these things in other words, so after stella's output log.txt gets a block,
# marked `stella_suite.sh:` at both ends, with one ORB-SLAM2 line per stella line of the same event
# (and the log line it stands for): new map created -> New Map created; resetting system -> System
# Reseting; tracking lost within N sec after initialization -> Track lost soon after initialisation;
# seems to be wrong initialization -> Wrong initialization; detect loop -> Loop detected; start loop
# bundle adjustment -> Starting Global Bundle Adjustment; dump keyframe trajectory -> Saving. The
# tracking times stella prints are read as they are; relocalisation is read from the trajectory.
# KITTI 00: run_kitti_slam with STOCK/stella_vslam/example/kitti/KITTI_mono_00-02.yaml into
# RUNS/kitti/CONF/kitti00/mono_I/ (KeyFrameTrajectory.txt), the configurations interleaved within
# each repeat, as kitti_runs.sh does.
# Every AFFINE_ORB_* variable of the caller is unset for each run, then the configuration's own set.
# Environment: SLAM_HARNESS (default ../shared/slam beside this project), KITTI_DATA (default
# ../shared/data/kitti00), TIMEOUT (per run, default 1200 s), WAIT_RENDER.
# Every step can be repeated: the runs are redone (--first to add more).
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
HARNESS=${SLAM_HARNESS:-$HERE/../../../shared/slam}
KITTI=${KITTI_DATA:-$HERE/../../../shared/data/kitti00}
STOCK=; ADAPTER=; RECOVERY=; RUN=; VOCAB=; SYNTH=/tmp/synth; RUNS=/tmp/stella_suite
SEEDS='1 2 3 4 5'; SEQUENCES='revisit_sweep oblique fast shake'; MODES='rgbd mono'
REPEATS=2; FIRST=1; KITTI_REPEATS=6; TABLES_ONLY=0; CONFS='S A0 V R'
TIMEOUT=${TIMEOUT:-1200}; WAIT_RENDER=${WAIT_RENDER:-3600}
usage() { sed -n '/^# usage/,/^# Every step/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }
while [ $# -gt 0 ]; do
  case $1 in
    --stock) STOCK=$2; shift 2;;
    --adapter) ADAPTER=$2; shift 2;;
    --recovery) RECOVERY=$2; shift 2;;
    --run) RUN=$2; shift 2;;
    --vocab) VOCAB=$2; shift 2;;
    --synth) SYNTH=$2; shift 2;;
    --runs) RUNS=$2; shift 2;;
    --seeds) SEEDS=$2; shift 2;;
    --sequences) SEQUENCES=$2; shift 2;;
    --modes) MODES=$2; shift 2;;
    --repeats) REPEATS=$2; shift 2;;
    --first) FIRST=$2; shift 2;;
    --kitti-repeats) KITTI_REPEATS=$2; shift 2;;
    --tables-only) TABLES_ONLY=1; shift;;
    --confs) CONFS=$2; shift 2;;
    *) usage;;
  esac
done
tables() {  # the configurations of CONFS that have runs, stock first
  local present=()
  for c in $CONFS; do [ -d "$RUNS/$c" ] || [ -d "$RUNS/kitti/$c" ] && present+=("$c"); done
  local synth=()
  for c in "${present[@]}"; do [ -f "$RUNS/$c/config.txt" ] && synth+=("$c"); done
  [ ${#synth[@]} -eq 0 ] ||
    /usr/bin/python3 "$HARNESS/analyze.py" --runs "$RUNS" --seqs "$SYNTH" --confs "${synth[*]}" > /dev/null
  [ -f "$RUNS/runs.csv" ] || echo "conf,seq,mode,run" > "$RUNS/runs.csv"  # KITTI alone
  [ -d "$RUNS/kitti" ] && /usr/bin/python3 "$HARNESS/kitti_to_tum.py" "$KITTI/poses.txt" "$KITTI/times.txt" \
    "$RUNS/kitti/groundtruth.txt" > /dev/null
  /usr/bin/python3 "$HERE/slam_tables.py" suite "$RUNS" "$SYNTH" "${present[@]}"
}
if [ "$TABLES_ONLY" = 1 ]; then tables; exit 0; fi
if [ -z "$STOCK" ] || [ -z "$ADAPTER" ]; then usage; fi
STOCK=$(readlink -f "$STOCK"); ADAPTER=$(readlink -f "$ADAPTER"); [ -z "$RECOVERY" ] || RECOVERY=$(readlink -f "$RECOVERY")
VOCAB=${VOCAB:-$STOCK/../vocab/orb_k10_L5.fbow}
[ -f "$VOCAB" ] || { echo "vocabulary not found: $VOCAB (--vocab)" >&2; exit 2; }
VOCAB=$(readlink -f "$VOCAB")
EXTRACTOR=src/stella_vslam/feature/orb_extractor.cc
for t in "$STOCK" "$ADAPTER" ${RECOVERY:+"$RECOVERY"}; do
  [ -f "$t/stella_vslam/$EXTRACTOR" ] || { echo "$t: no stella_vslam/$EXTRACTOR (not a build_stella.sh tree)" >&2; exit 2; }
  for r in run_tum_rgbd_slam run_image_slam run_kitti_slam; do
    [ -x "$t/build/examples/$r" ] || { echo "$t: no build/examples/$r (build_stella.sh)" >&2; exit 2; }
  done
done
for t in "$ADAPTER" ${RECOVERY:+"$RECOVERY"}; do
  [ -f "$t/stella_vslam/.affine_orb_backup/$EXTRACTOR" ] ||
    { echo "$t: no adapter (no .affine_orb_backup/$EXTRACTOR; build_stella.sh --affine PROJECT)" >&2; exit 2; }
  [ "$t/install/lib/libstella_vslam.so" -nt "$t/stella_vslam/$EXTRACTOR" ] ||
    { echo "$t: the library is older than the installed adapter: rebuild (build_stella.sh --tree NAME)" >&2; exit 2; }
done
[ -z "$RECOVERY" ] || grep -q "affine_orb recovery mode" "$RECOVERY/stella_vslam/src/stella_vslam/system.cc" ||
  { echo "$RECOVERY: no recovery lines in system.cc (adapters/stella_vslam/install.sh --recovery)" >&2; exit 2; }
[ ! -e "$STOCK/stella_vslam/.affine_orb_backup" ] ||
  { echo "$STOCK: holds the adapter (.affine_orb_backup/): not a stock tree" >&2; exit 2; }
for m in $MODES; do [ "$m" = rgbd ] || [ "$m" = mono ] || { echo "bad mode: $m" >&2; exit 2; }; done
mkdir -p "$RUNS"; RUNS=$(readlink -f "$RUNS"); SYNTH=$(readlink -f "$SYNTH")

declare -A TREE ENVS KIND
NAMES=(S A0 V)
TREE[S]=$STOCK; KIND[S]=stock; ENVS[S]=
TREE[A0]=$ADAPTER; KIND[A0]=affine; ENVS[A0]=
TREE[V]=$ADAPTER; KIND[V]=affine; ENVS[V]=AFFINE_ORB_MAX_TILT=2.83
[ -z "$RECOVERY" ] || { NAMES+=(R); TREE[R]=$RECOVERY; KIND[R]=affine; ENVS[R]=; }
if [ -n "$RUN" ]; then
  for name in $RUN; do [ -n "${TREE[$name]:-}" ] || { echo "--run: no configuration $name" >&2; exit 2; }; done
  read -r -a NAMES <<< "$RUN"
fi
record() {  # RUNS_ROOT NAME: its config.txt as run.sh writes it; a name used for another is refused
  local desc="$2=${KIND[$2]}${ENVS[$2]:+ ${ENVS[$2]}}"$'\n'"tree: ${TREE[$2]}"
  mkdir -p "$1/$2"
  if [ -f "$1/$2/config.txt" ]; then
    [ "$(cat "$1/$2/config.txt")" = "$desc" ] || {
      echo "$1/$2 holds runs of another configuration:" >&2; cat "$1/$2/config.txt" >&2; exit 2; }
  else
    echo "$desc" > "$1/$2/config.txt"
  fi
}
UNSET=()
for v in $(compgen -e | grep '^AFFINE_ORB_' || true); do UNSET+=(-u "$v"); done
TSLINE='import sys, time
t0 = time.monotonic()
with open(sys.argv[1], "w") as f:
    for line in sys.stdin:
        f.write("[%9.3f] %s" % (time.monotonic() - t0, line)); f.flush()'

key() { sed -n "s/^$1:[[:space:]]*\([^#[:space:]]*\).*/\1/p" "$2" | head -1; }
section() {  # the lines of a top-level YAML section, header included
  awk -v s="$1:" '$0 == s {p = 1; print; next} /^[^[:space:]]/ {p = 0} p && NF' "$2"
}
stella_yaml() {  # RENDER MODE OUT: stella's config for the render, from its camera.yaml (ORB-SLAM keys)
  local c=$1/camera.yaml mode=$2 out=$3 example setup order k v
  example=$STOCK/stella_vslam/example/tum_rgbd/TUM_RGBD_${mode}_1.yaml
  [ -f "$example" ] || { echo "no $example" >&2; exit 2; }
  for k in Camera.fx Camera.fy Camera.cx Camera.cy Camera.k1 Camera.k2 Camera.p1 Camera.p2 Camera.k3 \
           Camera.fps Camera.width Camera.height Camera.RGB ORBextractor.scaleFactor ORBextractor.nLevels \
           ORBextractor.iniThFAST ORBextractor.minThFAST; do
    [ -n "$(key "$k" "$c")" ] || { echo "$c: no $k" >&2; exit 2; }
  done
  setup=monocular; [ "$mode" = rgbd ] && setup=RGBD
  order=BGR; [ "$(key Camera.RGB "$c")" = 1 ] && order=RGB
  {
    echo "# stella_vslam config of $(basename "$1") ($mode), written by stella_suite.sh from $c"
    echo "# and the Tracking/Mapping sections of $example"
    echo "Camera:"
    echo "  name: \"$(basename "$1") $mode\""
    echo "  setup: \"$setup\""
    echo "  model: \"perspective\""
    for k in fx fy cx cy k1 k2 p1 p2 k3 fps; do echo "  $k: $(key "Camera.$k" "$c")"; done
    echo "  cols: $(key Camera.width "$c")"
    echo "  rows: $(key Camera.height "$c")"
    if [ "$mode" = rgbd ]; then
      for k in Camera.bf ThDepth; do [ -n "$(key "$k" "$c")" ] || { echo "$c: no $k" >&2; exit 2; }; done
      echo "  focal_x_baseline: $(key Camera.bf "$c")"
      echo "  depth_threshold: $(key ThDepth "$c")"
    fi
    echo "  color_order: \"$order\""
    section Tracking "$example"
    echo "Preprocessing:"
    echo "  min_size: 800"
    if [ "$mode" = rgbd ]; then
      v=$(key DepthMapFactor "$c"); [ -n "$v" ] || { echo "$c: no DepthMapFactor" >&2; exit 2; }
      echo "  depthmap_factor: $v"
    fi
    echo "Feature:"
    echo "  name: \"default ORB feature extraction setting\""
    echo "  scale_factor: $(key ORBextractor.scaleFactor "$c")"
    echo "  num_levels: $(key ORBextractor.nLevels "$c")"
    echo "  ini_fast_threshold: $(key ORBextractor.iniThFAST "$c")"
    echo "  min_fast_threshold: $(key ORBextractor.minThFAST "$c")"
    section Mapping "$example"
  } > "$out"
}
orbslam_words() {  # LOG: the block of ORB-SLAM2 lines analyze.py counts, one per stella line of the event
  awk '
    /new map created/                     {w = "New Map created"}
    /resetting system/                    {w = "System Reseting"}
    /tracking lost within .* after initialization/ {w = "Track lost soon after initialisation"}
    /seems to be wrong initialization/    {w = "Wrong initialization"}
    /detect loop: keyframe/               {w = "Loop detected"}
    /start loop bundle adjustment/        {w = "Starting Global Bundle Adjustment"}
    /dump keyframe trajectory/            {w = "Saving keyframe trajectory"}
    w != "" {out[++n] = w " (stella: log line " NR ")"; w = ""}
    END {
      print "--- stella_suite.sh: ORB-SLAM2 words for ../shared/slam/analyze.py, from stella'"'"'s lines above ---"
      for (i = 1; i <= n; i++) print out[i]
      print "--- stella_suite.sh: end ---"
    }' "$1"
}
run() {  # D NAME CMD...: one run into D, as run.sh makes it
  local D=$1 name=$2; shift 2
  rm -rf "$D"; mkdir -p "$D"; cd "$D"
  # shellcheck disable=SC2206  # ENVS holds VAR=VALUE words
  local FULL=(env "${UNSET[@]}" ${ENVS[$name]} "$@" --auto-term --viewer none --eval-log-dir "$D")
  echo "${FULL[@]}" > cmd.txt
  date -Is > start.txt; uptime > load_start.txt
  set +e
  /usr/bin/time -v -o time.txt timeout -k 10 "$TIMEOUT" "${FULL[@]}" 2>&1 | /usr/bin/python3 -u -c "$TSLINE" log.txt
  echo "${PIPESTATUS[0]}" > rc.txt
  set -e
  date -Is > end.txt; uptime > load_end.txt
  [ ! -f frame_trajectory.txt ] || cp frame_trajectory.txt CameraTrajectory.txt
  [ ! -f keyframe_trajectory.txt ] || cp keyframe_trajectory.txt KeyFrameTrajectory.txt
  orbslam_words log.txt > words.txt; cat words.txt >> log.txt; rm words.txt
  cd "$RUNS"
}

# Seeds outermost; within each sequence and repeat the configurations interleaved.
if [ -n "$SEQUENCES" ] && [ -n "$SEEDS" ]; then
  for name in "${NAMES[@]}"; do record "$RUNS" "$name"; done
  mkdir -p "$RUNS/stella_configs"
fi
for seed in $SEEDS; do
  for s in $SEQUENCES; do
    seq=${s}_s$seed; R=$SYNTH/$seq
    waited=0
    while [ ! -f "$R/render_done.txt" ]; do
      [ "$waited" -lt "$WAIT_RENDER" ] || { echo "$(date -Is) no render_done.txt in $R after ${WAIT_RENDER} s: skipped" >&2; continue 2; }
      [ "$waited" -gt 0 ] || echo "$(date -Is) waiting for $R/render_done.txt"
      sleep 30; waited=$((waited + 30))
    done
    first=$(awk '!/^#/ && NF {print $1; exit}' "$R/rgb.txt")
    [ "$(ls "$R/rgb" | wc -l)" = "$(awk '!/^#/ && NF' "$R/rgb.txt" | wc -l)" ] ||
      { echo "$R: rgb/ holds other files than rgb.txt lists (run_image_slam reads the folder)" >&2; exit 2; }
    for m in $MODES; do stella_yaml "$R" "$m" "$RUNS/stella_configs/${seq}_$m.yaml"; done
    for i in $(seq "$FIRST" $((FIRST + REPEATS - 1))); do
      for m in $MODES; do
        Y=$RUNS/stella_configs/${seq}_$m.yaml
        for name in "${NAMES[@]}"; do
          B=${TREE[$name]}/build/examples
          echo "$(date -Is) start $name $seq $m $i"
          if [ "$m" = rgbd ]; then
            run "$RUNS/$name/$seq/${m}_$i" "$name" "$B/run_tum_rgbd_slam" -v "$VOCAB" -d "$R" -c "$Y"
          else
            run "$RUNS/$name/$seq/${m}_$i" "$name" "$B/run_image_slam" -v "$VOCAB" -d "$R/rgb" -c "$Y" \
              --start-timestamp "$first"
          fi
          echo "$(date -Is) done  $name $seq $m $i rc=$(cat "$RUNS/$name/$seq/${m}_$i/rc.txt")"
        done
      done
    done
  done
done
if [ "$KITTI_REPEATS" -gt 0 ]; then
  [ -f "$KITTI/times.txt" ] || { echo "KITTI frames not found: $KITTI (KITTI_DATA)" >&2; exit 2; }
  KITTI=$(readlink -f "$KITTI")
  for name in "${NAMES[@]}"; do record "$RUNS/kitti" "$name"; done
  for i in $(seq "$FIRST" $((FIRST + KITTI_REPEATS - 1))); do
    for name in "${NAMES[@]}"; do
      run "$RUNS/kitti/$name/kitti00/mono_$i" "$name" "${TREE[$name]}/build/examples/run_kitti_slam" \
        -v "$VOCAB" -d "$KITTI" -c "$STOCK/stella_vslam/example/kitti/KITTI_mono_00-02.yaml"
      echo "$(date -Is) kitti $name $i rc=$(cat "$RUNS/kitti/$name/kitti00/mono_$i/rc.txt")"
    done
  done
fi
tables
