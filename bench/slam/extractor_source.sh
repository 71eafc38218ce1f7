# shellcheck shell=bash
# extractor_source.sh -- sourced by walk.sh and init_chain.sh: compiles a measuring program against one
# ORBextractor, so that stock's figures and the adapter's come from the same code. SOURCE is either
#   an ORB-SLAM2 or ORB-SLAM3 tree: its own src/ORBextractor.cc (stock), or the adapter that
#     adapters/orbslam*/install.sh put there (then with the affine_orb checkout its CMakeLists.txt names);
#   an affine_orb checkout (e.g. `git archive REV include adapters | tar -x -C DIR`): its ORB-SLAM2 adapter.
# Environment: CXX (default g++).

# extractor_check SOURCE: exits with 2 unless SOURCE is one of the above.
extractor_check() {
  [ -f "$1/adapters/orbslam2/ORBextractor.cc" ] || [ -f "$1/src/ORBextractor.cc" ] ||
    { echo "$1: neither an ORB-SLAM tree nor an affine_orb checkout" >&2; exit 2; }
}

# extractor_compile SOURCE PROGRAM OUTPUT [FLAG...]: PROGRAM.cpp with SOURCE's ORBextractor.cc; an
# ORB-SLAM3 tree defines WALK_ORBSLAM3, which fork_extractor.hpp reads.
extractor_compile() {
  local src program output cc opencv
  src=$(readlink -f "$1"); program=$2; output=$3; shift 3
  local flags=(-O2 -std=c++17 -w "$@")
  if [ -f "$src/adapters/orbslam2/ORBextractor.cc" ]; then  # an affine_orb checkout
    cc=$src/adapters/orbslam2/ORBextractor.cc
    flags+=(-I"$src/adapters/orbslam2" -I"$src/adapters/common" -I"$src/include" -I/usr/include/eigen3)
  else  # a fork
    cc=$src/src/ORBextractor.cc
    flags+=(-I"$src/include")
    grep -q 'namespace ORB_SLAM3' "$src/include/ORBextractor.h" && flags+=(-DWALK_ORBSLAM3)
    local affine
    affine=$(sed -n 's/^set(AFFINE_ORB_DIR "\(.*\)")$/\1/p' "$src/CMakeLists.txt")
    [ -n "$affine" ] && flags+=(-I"$affine/include" -I"$affine/adapters/common" -I/usr/include/eigen3)
  fi
  opencv=$(pkg-config --cflags --libs opencv4)
  # shellcheck disable=SC2086  # opencv holds several words
  ${CXX:-g++} "${flags[@]}" "$program" "$cc" -o "$output" $opencv
}
