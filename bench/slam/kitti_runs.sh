#!/bin/bash
# kitti_runs.sh RUNS FIRST REPEATS 'NAME=TREE [VAR=VALUE ...]'... -- ORB-SLAM's mono_kitti on the
# KITTI 00 frames of ../shared/data/kitti00, one run at a time, the configurations interleaved within
# each repeat (so that a change of machine load touches them alike). A configuration is a fork tree
# (ORB-SLAM2 or ORB-SLAM3, built with mono_kitti) and the environment it runs with; every other
# AFFINE_ORB_* variable is unset. Each run goes to RUNS/NAME/kitti00/mono_I: log.txt (the example's
# output), KeyFrameTrajectory.txt, time.txt (/usr/bin/time -v), rc.txt, load_start/end.txt
# (uptime). Then: bench/slam/slam_tables.py kitti RUNS GROUNDTRUTH NAME... (GROUNDTRUTH from
# ../shared/slam/kitti_to_tum.py). Environment: VOCAB (default /tmp/orbslam2/voc.txt), KITTI_DATA
# (default ../shared/data/kitti00 beside this project), YAML (default
# TREE/Examples/Monocular/KITTI00-02.yaml), TIMEOUT (default 600 s).
set -u
[ $# -ge 4 ] || { sed -n '2,12p' "$0"; exit 2; }
RUNS=$1; FIRST=$2; REPEATS=$3; shift 3
HERE=$(cd "$(dirname "$0")" && pwd)
VOCAB=${VOCAB:-/tmp/orbslam2/voc.txt}
DATA=${KITTI_DATA:-$HERE/../../../shared/data/kitti00}
[ -f "$VOCAB" ] || { echo "vocabulary not found: $VOCAB (VOCAB)" >&2; exit 2; }
[ -f "$DATA/times.txt" ] || { echo "KITTI frames not found: $DATA (KITTI_DATA)" >&2; exit 2; }
UNSET=()
for v in $(compgen -e | grep '^AFFINE_ORB_' || true); do UNSET+=(-u "$v"); done
for i in $(seq "$FIRST" $((FIRST + REPEATS - 1))); do
  for conf in "$@"; do
    name=${conf%%=*}; rest=${conf#*=}; read -r tree envs <<< "$rest"
    D=$RUNS/$name/kitti00/mono_$i
    rm -rf "$D"; mkdir -p "$D"; cd "$D" || exit 1
    uptime > load_start.txt
    # shellcheck disable=SC2086  # envs holds VAR=VALUE words
    /usr/bin/time -v -o time.txt timeout -k 10 "${TIMEOUT:-600}" env "${UNSET[@]}" $envs \
      "$tree/Examples/Monocular/mono_kitti" "$VOCAB" "${YAML:-$tree/Examples/Monocular/KITTI00-02.yaml}" "$DATA" \
      > log.txt 2>&1
    echo $? > rc.txt; uptime > load_end.txt
    echo "$(date -Is) $name $i rc=$(cat rc.txt)"
  done
done
