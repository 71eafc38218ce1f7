#!/bin/bash
# build_orbslam3.sh -- build ORB-SLAM3 (github.com/shanpenghui/ORB_SLAM3_Fixed, 060181f, V1.0) headless
# on Debian 12 (GCC 12, OpenCV 4.6, Eigen 3.4, no Pangolin), with the examples in $TARGETS, in its
# own tree (outside the project), stock or with affine_orb's adapter installed.
#
# usage:
#   build_orbslam3.sh DIR
#       DIR = a checkout of ORB_SLAM3_Fixed (060181f; a sparse checkout without the IMU data, PDFs
#       and Vocabulary/ORBvoc.txt.tar.gz is enough). The first run applies the fixes below; every run
#       builds what is missing or out of date: Thirdparty/DBoW2, Thirdparty/g2o, lib/libORB_SLAM3.so
#       and the examples (Release, -j$JOBS). Run it again after a failure or a change to the tree.
#
# An adapter tree: a copy of a built stock tree, the adapter installed, rebuilt by this script (the
# copy keeps the Thirdparty libraries, built from the same sources; only the library and the
# examples are compiled again):
#   cp -a STOCK REC && rm -rf REC/build
#   adapters/orbslam3/install.sh --recovery REC      # refuses a build/ configured for STOCK
#   build_orbslam3.sh REC
# (A build directory that a copy took over from another tree is removed and configured afresh:
# `make` there would rebuild the other tree.)
#
# env: JOBS (default 2), TARGETS (default "rgbd_tum mono_tum mono_kitti": executables of ORB-SLAM3's
#      CMakeLists.txt; "all" builds every example, Examples_old's too)
#
# Debian 12 packages (installed with apt-get install -y when missing, needs root): build-essential
# cmake libeigen3-dev libopencv-dev libboost-serialization-dev (Atlas save/load; the library links
# -lboost_serialization) libssl-dev (-lcrypto: MD5 of the vocabulary file, System.cc).
#
# Vocabulary: the examples take a text vocabulary (System.cc calls loadFromTextFile), e.g. ORB-SLAM2's,
# which the project's runs use:
#   gunzip -c ../shared/data/orbslam2_vocabulary/vocabulary_k10_L5.txt.gz > VOC.txt
#   DIR/Examples/Monocular/mono_kitti VOC.txt DIR/Examples/Monocular/KITTI00-02.yaml KITTI_SEQUENCE
# The renders' camera.yaml needs `Camera.type: "PinHole"` appended (bench/slam/suite.sh does it).
#
# Fixes (none in tracking, mapping or loop-closing code; 060181f already builds with OpenCV 4 and
# GCC 12 as far as the library and the examples go), applied once with sed/awk, idempotent via the
# marker file DIR/.headless_patched:
#  CMake    : find_package(Pangolin), its include and link lines dropped (Pangolin is not packaged in
#             Debian 12); find_package(Glog) and glog::glog dropped (linked, but no file includes
#             glog); add_subdirectory(Thirdparty/g2o) dropped: g2o is built once, in
#             Thirdparty/g2o/build as upstream's build.sh does (which the main build then compiled a
#             second time into the same lib/libg2o.so), so that a copied tree keeps it.
#             Configured with -DCMAKE_DISABLE_FIND_PACKAGE_realsense2=ON (no RealSense examples).
#  C++ std  : DBoW2 and g2o compiled with -std=c++11, the library's standard (GCC 12 defaults to
#             gnu++17; a C++17 g2o beside the C++11 ORB-SLAM2 crashed in its first bundle adjustment,
#             docs/slam.md), as g2o was when the main build compiled it
#  headless : include/Map.h: <pangolin/pangolin.h> replaced by a GLubyte typedef (Map keeps a
#             GLubyte* thumbnail, never drawn); include/MapDrawer.h: pangolin::OpenGlMatrix stubbed;
#             src/MapDrawer.cc: the OpenGL bodies of DrawMapPoints, DrawKeyFrames, DrawCurrentCamera
#             and GetCurrentOpenGLCameraMatrix emptied; src/Viewer.cc: Run() reduced to SetFinish();
#             src/System.cc: the pangolin include dropped (its uses are commented out in 060181f);
#             every example in Examples/ and Examples_old/ starts the System with bUseViewer=false
#             (FrameDrawer draws with OpenCV only: unchanged, and unused without the viewer)
set -euo pipefail
JOBS=${JOBS:-2}
TARGETS=${TARGETS:-"rgbd_tum mono_tum mono_kitti"}
HERE=$(cd "$(dirname "$0")" && pwd)
usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }
case "${1:-}" in
  ""|-h|--help) usage ;;
esac
[ $# -eq 1 ] || usage
D=$(readlink -f "$1")
step() { echo "== $(date -u +%T) $*"; }

# --- the tree: ORB-SLAM3 alone has include/Atlas.h; its System.h declares namespace ORB_SLAM3
if [ ! -f "$D/include/Atlas.h" ] || ! grep -q '^ *namespace ORB_SLAM3' "$D/include/System.h" 2>/dev/null ||
   ! grep -q '^project(ORB_SLAM3)' "$D/CMakeLists.txt" 2>/dev/null || [ ! -f "$D/src/Viewer.cc" ]; then
  echo "$D is not an ORB-SLAM3 checkout (no include/Atlas.h, namespace ORB_SLAM3 in include/System.h," \
       "project(ORB_SLAM3) in CMakeLists.txt and src/Viewer.cc)" >&2
  exit 2
fi
cd "$D"

# --- Debian packages
# shellcheck source=bench/slam/debian_packages.sh
. "$HERE/debian_packages.sh"
install_missing build-essential cmake libeigen3-dev libopencv-dev libboost-serialization-dev libssl-dev

# --- the fixes
# empty_bodies FILE REGEX BODY N: the body of each function whose signature line matches REGEX (its
# "{" alone on the next line, its "}" the next line starting with "}") becomes the line BODY; N such
# functions must be found (a body that is BODY already counts, so a second run changes nothing)
empty_bodies() {
  awk -v re="$2" -v body="$3" '
    skip { if ($0 ~ /^}/) { print body; skip = 0; n++ }; next }
    $0 ~ re { print; if ((getline) <= 0) exit 1
              if ($0 == body) { print; n++; next }
              if ($0 !~ /^\{[ \t]*$/) { print "unexpected: " $0 > "/dev/stderr"; exit 1 }
              skip = 1; next }
    { print }
    END { if (skip) exit 1; print n + 0 > "/dev/stderr" }' "$1" 2> "$1.count" > "$1.new" || true
  local n; n=$(tail -n 1 "$1.count"); sed '$d' "$1.count" >&2; rm -f "$1.count"
  [ "$n" = "$4" ] || { rm -f "$1.new"; echo "$1: $n of $4 function bodies found for $2" >&2; exit 1; }
  mv "$1.new" "$1"
}
if [ ! -f .headless_patched ]; then
  step "headless fixes"
  # CMake: no Pangolin, no glog, g2o built on its own
  # shellcheck disable=SC2016  # CMake variables, not the shell's
  sed -i '/^find_package(Pangolin REQUIRED)/d; /^\${Pangolin_INCLUDE_DIRS}$/d; /^\${Pangolin_LIBRARIES}$/d
          /^find_package(Glog)$/d; /^glog::glog$/d; /^add_subdirectory(Thirdparty\/g2o)$/d' CMakeLists.txt
  # headers: the GL type Map keeps, pangolin's matrix type MapDrawer's signatures name
  sed -i 's|^#include <pangolin/pangolin.h>$|typedef unsigned char GLubyte;  // headless: no pangolin/GL|' include/Map.h
  sed -i 's|^#include<pangolin/pangolin.h>$|namespace pangolin { struct OpenGlMatrix {}; }  // headless stub|' include/MapDrawer.h
  sed -i '/^#include <pangolin\/pangolin.h>$/d' src/System.cc src/MapDrawer.cc src/Viewer.cc
  empty_bodies src/MapDrawer.cc \
    '^void MapDrawer::(DrawMapPoints|DrawKeyFrames|DrawCurrentCamera|GetCurrentOpenGLCameraMatrix)\(' '{}' 4
  empty_bodies src/Viewer.cc '^void Viewer::Run\(\)' '{ SetFinish(); }' 1
  # examples: ORB_SLAM3::System SLAM(argv[1],argv[2],<sensor>, true ...) -> false
  sed -i 's/\(ORB_SLAM3::System SLAM(argv\[1\], *argv\[2\], *ORB_SLAM3::System::[A-Z_]*, *\)true/\1false/' \
    Examples/*/*.cc Examples_old/*/*.cc
  # what must be gone
  left=$( { grep -n -i 'pangolin\|glog\|add_subdirectory' CMakeLists.txt
             grep -n 'pangolin' include/*.h src/*.cc | grep -v 'headless\|pangolin::OpenGlMatrix\|BindToContext(.*\*/$'
             grep -n 'GL_\|\bgl[A-Z]' src/MapDrawer.cc src/Viewer.cc
             grep -n 'System SLAM(.*System::[A-Z_]*, *true' Examples/*/*.cc Examples_old/*/*.cc; } || true)
  [ -z "$left" ] || { echo "not patched as expected (another commit?):"; echo "$left"; exit 1; } >&2
  touch .headless_patched
fi

# --- build directories taken over from another tree by cp -a: `make` there builds the other tree
for b in build Thirdparty/DBoW2/build Thirdparty/g2o/build; do
  c=$D/$b/CMakeCache.txt
  [ -f "$c" ] || continue
  home=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$c")
  src=$D; [ "$b" = build ] || src=$D/${b%/build}
  if [ "$home" != "$src" ]; then
    step "$b was configured for ${home:-another tree}: removed"
    rm -rf "${D:?}/$b"
  fi
done

# cmake_build SRC [cmake args...] -- [make targets]: configure SRC/build (logged), make -j$JOBS
cmake_build() {
  local src=$1; shift
  local args=() targets=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do args+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  targets=("$@")
  mkdir -p "$src/build"
  cmake -S "$src" -B "$src/build" -DCMAKE_BUILD_TYPE=Release "${args[@]}" > "$src/build/cmake.log" 2>&1 ||
    { cat "$src/build/cmake.log"; exit 1; }
  make -C "$src/build" -j"$JOBS" "${targets[@]}"
}

# --- Thirdparty: built when its library is missing or its build directory is this tree's (make is
# then quick when nothing changed); a copy whose build directory was removed above keeps the
# library it copied. Sophus is header-only (Thirdparty/Sophus on the include path): nothing to build.
for t in DBoW2 g2o; do
  if [ -d "$D/Thirdparty/$t/build" ] || [ ! -f "$D/Thirdparty/$t/lib/lib$t.so" ]; then
    step "Thirdparty/$t"
    cmake_build "$D/Thirdparty/$t" -DCMAKE_CXX_FLAGS=-std=c++11
  else
    step "Thirdparty/$t: lib/lib$t.so kept (copied, no build directory)"
  fi
done

# --- the library and the examples
step "ORB_SLAM3 $TARGETS"
if [ "$TARGETS" = all ]; then
  cmake_build "$D" -DCMAKE_DISABLE_FIND_PACKAGE_realsense2=ON
else
  # shellcheck disable=SC2086
  cmake_build "$D" -DCMAKE_DISABLE_FIND_PACKAGE_realsense2=ON -- ORB_SLAM3 $TARGETS
fi
# every example finds this tree's libraries
for t in $TARGETS; do
  [ "$t" = all ] && break
  exe=$(find "$D/Examples" "$D/Examples_old" -maxdepth 2 -type f -name "$t" -perm -u+x | head -n 1)
  [ -n "$exe" ] || { echo "$t: no executable under Examples/" >&2; exit 1; }
  libs=$(ldd "$exe")
  if grep -q "not found" <<< "$libs"; then echo "$libs" >&2; exit 1; fi
  for l in libORB_SLAM3 libDBoW2 libg2o; do
    grep -q "$l.so => $D/" <<< "$libs" || { echo "$exe: $l.so not loaded from $D:" >&2; echo "$libs" >&2; exit 1; }
  done
done
echo "BUILD_OK $D"
