#!/bin/bash
# build_stella.sh -- build stella_vslam (github.com/stella-cv/stella_vslam, b0e60d6) headless on
# Debian 12 (GCC 12, OpenCV 4.6, Eigen 3.4), with the runners of stella_vslam_examples, and
# optionally a second tree with affine_orb's adapter installed.
#
# usage:
#   build_stella.sh [--prefix DIR] [--src DIR] --stella SRC --examples SRC --g2o SRC --fbow SRC \
#                   --tinycolormap SRC --filesystem SRC
#       SRC = anything `git clone` takes (a checkout or a bare mirror); only needed while the clone
#       under --src is missing. Builds the stock tree, PREFIX/stock/stella_vslam.
#   build_stella.sh [--prefix DIR] --affine PROJECT
#       PROJECT = an affine_orb checkout: PREFIX/affine/stella_vslam := cp -a of the stock tree (first
#       time), PROJECT/adapters/stella_vslam/install.sh on it, then built like the stock tree.
#   build_stella.sh [--prefix DIR] --tree NAME
#       rebuild PREFIX/NAME/stella_vslam as it is (e.g. after changing or uninstalling the adapter).
#
# What it builds (every step skips what is done; run it again after a failure):
#   apt      missing Debian 12 packages (apt-get install -y, needs root): build-essential cmake git
#            libeigen3-dev libopencv-dev libyaml-cpp-dev libsqlite3-dev libsuitesparse-dev (CSparse for
#            g2o) libspdlog-dev ccache python3
#   g2o      RainerKuemmerle/g2o at tag 20230223_git (e8df200, the tag stella's Dockerfiles use; not
#            packaged in Debian 12), shared, CSparse on, no CHOLMOD/OpenGL/OpenMP/apps/examples, only
#            the types stella links (sba, sim3, slam3d) -> PREFIX/deps
#   FBoW     stella-cv/FBoW at c6e3c29 (the commit stella's 3rd/FBoW submodule names), with its utils
#            -> PREFIX/deps (stella then uses it instead of its submodule)
#   stella   stella-cv/stella_vslam at $STELLA_COMMIT (clone: PREFIX/NAME/stella_vslam; submodule
#            3rd/tinycolormap from --tinycolormap at the commit stella names; 3rd/FBoW left empty),
#            Release, no tests, built in PREFIX/NAME/build/stella_vslam, installed in PREFIX/NAME/install
#   vocab    PREFIX/vocab/orb_k10_L5.fbow: dbow2_to_fbow.py (beside this script) on $VOCAB_TXT, the
#            DBoW2 text vocabulary of ../shared/data/orbslam2_vocabulary (ORB-SLAM2's layout, trained
#            with ORB-SLAM2's extractor; its README): the same tree in FBoW's binary format
#   examples stella-cv/stella_vslam_examples at defc69e (submodule 3rd/filesystem from --filesystem)
#            against PREFIX/NAME/install; only the runners in $RUNNERS, in PREFIX/NAME/build/examples
# Build directories are outside the source trees, so `cp -a` of a tree and `git status` stay clean.
# stella compiles through ccache (its USE_CCACHE) with CCACHE_DIR=PREFIX/ccache and
# CCACHE_BASEDIR=PREFIX: every tree sits at the same depth, so the compile lines of the affine tree
# are the stock tree's but for the adapter's file, and its build takes the rest from the cache.
#
# Fixes: none to any source. Headless: stella_vslam_examples links a viewer only when
# find_package(pangolin_viewer / socket_publisher / iridescence_viewer) succeeds; the script
# disables those three lookups (CMAKE_DISABLE_FIND_PACKAGE_*), so no viewer is built or linked.
# Libraries and runners carry an RPATH to PREFIX/deps/lib and PREFIX/NAME/install/lib (no
# LD_LIBRARY_PATH needed).
#
# env: JOBS (default 2), NICE (default 19: every compiler runs under nice -n $NICE),
#      PREFIX (default /work/slam/stella), SRC_DIR (default /work/slam/src),
#      STELLA_COMMIT (default b0e60d6, the project's conformance reference),
#      RUNNERS (default "run_kitti_slam run_tum_rgbd_slam run_image_slam"),
#      VOCAB_TXT (default: the project's ../shared/data/orbslam2_vocabulary/vocabulary_k10_L5.txt.gz),
#      STELLA_SRC EXAMPLES_SRC G2O_SRC FBOW_SRC TINYCOLORMAP_SRC FILESYSTEM_SRC (as the options)
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
JOBS=${JOBS:-2}
NICE=${NICE:-19}
PREFIX=${PREFIX:-/work/slam/stella}
SRC_DIR=${SRC_DIR:-/work/slam/src}
STELLA_COMMIT=${STELLA_COMMIT:-b0e60d6}
RUNNERS=${RUNNERS:-"run_kitti_slam run_tum_rgbd_slam run_image_slam"}
G2O_COMMIT=20230223_git
FBOW_COMMIT=c6e3c29
EXAMPLES_COMMIT=defc69e
VOCAB_TXT=${VOCAB_TXT:-$HERE/../../../shared/data/orbslam2_vocabulary/vocabulary_k10_L5.txt.gz}
NAME=stock
AFFINE=
usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --prefix) PREFIX=$2; shift 2 ;;
    --src) SRC_DIR=$2; shift 2 ;;
    --stella) STELLA_SRC=$2; shift 2 ;;
    --examples) EXAMPLES_SRC=$2; shift 2 ;;
    --g2o) G2O_SRC=$2; shift 2 ;;
    --fbow) FBOW_SRC=$2; shift 2 ;;
    --tinycolormap) TINYCOLORMAP_SRC=$2; shift 2 ;;
    --filesystem) FILESYSTEM_SRC=$2; shift 2 ;;
    --affine) AFFINE=$(readlink -f "$2"); NAME=affine; shift 2 ;;
    --tree) NAME=$2; shift 2 ;;
    -h|--help) usage ;;
    *) echo "unknown argument: $1" >&2; usage ;;
  esac
done
mkdir -p "$PREFIX" "$SRC_DIR"
PREFIX=$(readlink -f "$PREFIX"); SRC_DIR=$(readlink -f "$SRC_DIR")
DEPS=$PREFIX/deps
TREE=$PREFIX/$NAME/stella_vslam
INSTALL=$PREFIX/$NAME/install
BUILD=$PREFIX/build  # g2o and FBoW
TBUILD=$PREFIX/$NAME/build
export CCACHE_DIR=$PREFIX/ccache CCACHE_BASEDIR=$PREFIX
N="nice -n $NICE"
step() { echo "== $(date -u +%T) $*"; }

# clone_at DIR SRC REV: a clone of SRC at REV in DIR (an existing DIR is checked out at REV)
clone_at() {
  if [ ! -d "$1/.git" ]; then
    [ -n "$2" ] || { echo "$1 is missing: give the source to clone it from (--help)" >&2; exit 2; }
    git clone -q "$2" "$1"
  fi
  git -C "$1" -c advice.detachedHead=false checkout -q "$3"
}

# cmake_build SRC BUILD [cmake args...] -- [make targets]: configure (logged), make -j$JOBS
cmake_build() {
  local src=$1 dir=$2; shift 2
  local args=() targets=()
  while [ $# -gt 0 ] && [ "$1" != -- ]; do args+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  targets=("$@")
  mkdir -p "$dir"
  $N cmake -S "$src" -B "$dir" "${args[@]}" > "$dir/cmake.log" 2>&1 || { cat "$dir/cmake.log"; exit 1; }
  $N make -C "$dir" -j"$JOBS" "${targets[@]}"
}

# --- Debian packages
# shellcheck source=bench/slam/debian_packages.sh
. "$HERE/debian_packages.sh"
install_missing build-essential cmake git libeigen3-dev libopencv-dev libyaml-cpp-dev libsqlite3-dev libsuitesparse-dev libspdlog-dev ccache python3

# --- g2o and FBoW -> PREFIX/deps
RPATH="$DEPS/lib;$INSTALL/lib"
COMMON=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$DEPS" -DCMAKE_INSTALL_RPATH="$RPATH"
        -DCMAKE_INSTALL_RPATH_USE_LINK_PATH=ON)
if [ ! -f "$DEPS/.g2o_$G2O_COMMIT" ]; then
  step g2o
  clone_at "$SRC_DIR/g2o" "${G2O_SRC:-}" "$G2O_COMMIT"
  cmake_build "$SRC_DIR/g2o" "$BUILD/deps/g2o" "${COMMON[@]}" -DCMAKE_INSTALL_PREFIX="$DEPS" \
    -DBUILD_SHARED_LIBS=ON -DBUILD_UNITTESTS=OFF -DG2O_USE_CHOLMOD=OFF -DG2O_USE_CSPARSE=ON \
    -DG2O_USE_OPENGL=OFF -DG2O_USE_OPENMP=OFF -DG2O_BUILD_APPS=OFF -DG2O_BUILD_EXAMPLES=OFF \
    -DG2O_BUILD_LINKED_APPS=OFF -DG2O_BUILD_BENCHMARKS=OFF -DG2O_BUILD_SLAM2D_TYPES=OFF \
    -DG2O_BUILD_SLAM2D_ADDON_TYPES=OFF -DG2O_BUILD_DATA_TYPES=OFF -DG2O_BUILD_SCLAM2D_TYPES=OFF \
    -DG2O_BUILD_ICP_TYPES=OFF -DG2O_BUILD_SLAM3D_ADDON_TYPES=OFF
  grep -q "Enable support for CSparse" "$BUILD/deps/g2o/cmake.log" || { echo "g2o: CSparse not found" >&2; exit 1; }
  make -C "$BUILD/deps/g2o" install > "$BUILD/deps/g2o/install.log"
  touch "$DEPS/.g2o_$G2O_COMMIT"
fi
if [ ! -f "$DEPS/.fbow_$FBOW_COMMIT" ]; then
  step FBoW
  clone_at "$SRC_DIR/FBoW" "${FBOW_SRC:-}" "$FBOW_COMMIT"
  cmake_build "$SRC_DIR/FBoW" "$BUILD/deps/FBoW" "${COMMON[@]}" -DCMAKE_INSTALL_PREFIX="$DEPS" \
    -DBUILD_SHARED_LIBS=ON -DBUILD_UTILS=ON -DBUILD_TESTS=OFF
  make -C "$BUILD/deps/FBoW" install > "$BUILD/deps/FBoW/install.log"
  touch "$DEPS/.fbow_$FBOW_COMMIT"
fi

# --- the vocabulary
VOCAB=$PREFIX/vocab/orb_k10_L5.fbow
if [ ! -f "$VOCAB" ]; then
  step "vocabulary $VOCAB"
  mkdir -p "$PREFIX/vocab"
  $N python3 "$HERE/dbow2_to_fbow.py" "$VOCAB_TXT" "$VOCAB.tmp" && mv "$VOCAB.tmp" "$VOCAB"
fi

# --- the stella_vslam tree
if [ -n "$AFFINE" ]; then
  [ -x "$AFFINE/adapters/stella_vslam/install.sh" ] || { echo "$AFFINE: not an affine_orb checkout" >&2; exit 2; }
  [ -d "$PREFIX/stock/stella_vslam/.git" ] || { echo "build the stock tree first ($PREFIX/stock)" >&2; exit 2; }
  if [ ! -d "$TREE" ]; then
    step "cp -a $PREFIX/stock/stella_vslam $TREE"
    mkdir -p "$PREFIX/$NAME"
    cp -a "$PREFIX/stock/stella_vslam" "$TREE"
  fi
  step "adapter install"
  "$AFFINE/adapters/stella_vslam/install.sh" --affine-orb "$AFFINE" "$TREE"
elif [ "$NAME" = stock ]; then
  clone_at "$TREE" "${STELLA_SRC:-}" "$STELLA_COMMIT"
fi
[ -d "$TREE/.git" ] || { echo "$TREE: no stella_vslam checkout" >&2; exit 2; }
if [ ! -f "$TREE/3rd/tinycolormap/include/tinycolormap.hpp" ]; then
  [ -n "${TINYCOLORMAP_SRC:-}" ] || { echo "$TREE/3rd/tinycolormap is empty: give --tinycolormap" >&2; exit 2; }
  git -C "$TREE" config submodule.3rd/tinycolormap.url "$(readlink -f "$TINYCOLORMAP_SRC")"
  git -C "$TREE" -c protocol.file.allow=always submodule update -q --init 3rd/tinycolormap
fi
echo "stella_vslam tree $TREE at $(git -C "$TREE" rev-parse --short HEAD)"
# the project's copy of b0e60d6's extractor, the reference the adapter is compared with
REF=$HERE/../../../shared/slam/stock_extractors/stella_vslam_b0e60d6/stella_vslam/feature/orb_extractor.cc
if [ -z "$AFFINE" ] && [ -f "$REF" ]; then
  if cmp -s "$REF" "$TREE/src/stella_vslam/feature/orb_extractor.cc"; then
    echo "feature/orb_extractor.cc: the same as ${REF#"$HERE/../../"}"
  else
    echo "WARNING: feature/orb_extractor.cc differs from ${REF#"$HERE/../../"}" >&2
  fi
fi
step "stella_vslam ($NAME)"
cmake_build "$TREE" "$TBUILD/stella_vslam" "${COMMON[@]}" -DCMAKE_INSTALL_PREFIX="$INSTALL" \
  -DBUILD_TESTS=OFF -DUSE_CCACHE=ON -DBOW_FRAMEWORK=FBoW
[ ! -d "$TBUILD/stella_vslam/3rd/FBoW" ] || { echo "stella built its own 3rd/FBoW, not $DEPS's" >&2; exit 1; }
make -C "$TBUILD/stella_vslam" install > "$TBUILD/stella_vslam/install.log"

# --- the runners
step "stella_vslam_examples ($NAME)"
clone_at "$SRC_DIR/stella_vslam_examples" "${EXAMPLES_SRC:-}" "$EXAMPLES_COMMIT"
EX=$SRC_DIR/stella_vslam_examples
if [ ! -f "$EX/3rd/filesystem/include/ghc/filesystem.hpp" ]; then
  [ -n "${FILESYSTEM_SRC:-}" ] || { echo "$EX/3rd/filesystem is empty: give --filesystem" >&2; exit 2; }
  git -C "$EX" config submodule.3rd/filesystem.url "$(readlink -f "$FILESYSTEM_SRC")"
  git -C "$EX" -c protocol.file.allow=always submodule update -q --init 3rd/filesystem
fi
# shellcheck disable=SC2086
cmake_build "$EX" "$TBUILD/examples" "${COMMON[@]}" -DCMAKE_PREFIX_PATH="$INSTALL;$DEPS" \
  -DCMAKE_DISABLE_FIND_PACKAGE_pangolin_viewer=ON -DCMAKE_DISABLE_FIND_PACKAGE_socket_publisher=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_iridescence_viewer=ON -- $RUNNERS
for r in $RUNNERS; do
  if ldd "$TBUILD/examples/$r" | grep -q "not found"; then ldd "$TBUILD/examples/$r"; exit 1; fi
done
echo "BUILD_OK $NAME $TREE -> $TBUILD/examples/{${RUNNERS// /,}}"
