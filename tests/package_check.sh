#!/usr/bin/env bash
# The Debian packages, as a user gets them (cmake/packaging.cmake; a stage of tests/run_all.sh):
#   1. a packaging build (prefix /usr, the library and the Python module only) and cpack: the files
#      libaffine-orb-dev_<version>_all.deb and python3-affine-orb_<version>_<arch>.deb;
#   2. `apt-get install ./<file>.deb` of both;
#   3. tests/consumer built against /usr with find_package(affine_orb) and with pkg-config, and run
#      (tests/consumer/check.cmake);
#   4. Debian's /usr/bin/python3, from /tmp and with no PYTHONPATH, imports the installed module
#      (/usr/lib/python3/dist-packages) and reports the version;
#   5. `apt-get remove` of both, and a check that their files are gone.
# It leaves the machine as it found it, also when a step fails: a trap removes the two packages and
# any missing dependency their installation brought in, so that nothing installed stays behind for the later
# stages (their tests must use the build tree's headers and module). Needs root, or sudo without a
# password; skipped, saying so, otherwise.
# A run that is killed (SIGKILL: no trap runs) leaves the packages installed. So the check keeps a
# stamp, /var/tmp/affine_orb_package_check.stamp, while its packages are installed: the time it
# began installing, the dependencies apt-get brought in, and after the installation each package's
# dpkg file list's modification time (dpkg rewrites the list on every installation). A run that finds
# the packages installed as the stamp says (the same times; no times yet and lists no older than the
# stamp, if the kill came during apt-get install) removes them and goes on. Installed in any other
# way (the user's copy), it refuses to run: it would replace that copy and then remove it.
# Build tree: ${AFFINE_ORB_BUILD_ROOT:-build}/package.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS

as_root=()
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
    as_root=(sudo -n)
  else
    echo "Debian packages: skipped, installing them needs root or password-less sudo"
    exit 0
  fi
fi

packages=(libaffine-orb-dev python3-affine-orb)
installed() { dpkg-query -W -f='${Status}\n' "$1" 2>/dev/null | grep -q "install ok installed"; }
stamp_file=/var/tmp/affine_orb_package_check.stamp
list_time() {  # modification time of dpkg's file list of package $1 (dpkg >= 1.19.3)
  dpkg-query -W -f='${db-fsys:Last-Modified}' "$1" 2>/dev/null || echo 0
}
export DEBIAN_FRONTEND=noninteractive
apt_get=(apt-get -q -o DPkg::Lock::Timeout=300)  # waits for another apt-get instead of failing

present=()
for p in "${packages[@]}"; do installed "$p" && present+=("$p"); done
if ((${#present[@]})); then
  ours=0
  if [[ -f $stamp_file ]]; then
    ours=1
    since=$(sed -n 's/^since //p' "$stamp_file")
    for p in "${present[@]}"; do
      recorded=$(sed -n "s/^time $p //p" "$stamp_file")
      now=$(list_time "$p")
      if [[ -n $recorded ]]; then
        [[ $recorded == "$now" ]] || ours=0
      else
        [[ -n $since ]] && ((now >= since)) || ours=0
      fi
    done
  fi
  if ((ours)); then
    leftover=("${present[@]}")
    for p in $(sed -n 's/^extra //p' "$stamp_file"); do installed "$p" && leftover+=("$p"); done
    echo "Debian packages: removing what a killed run of this check left installed: ${leftover[*]}"
    "${as_root[@]}" "${apt_get[@]}" remove -y "${leftover[@]}" > /dev/null ||
      { echo "Debian packages: apt-get remove ${leftover[*]} failed" >&2; exit 1; }
  else
    for p in "${present[@]}"; do
      echo "Debian packages: $p is installed already, not by this check; remove it first (apt-get remove $p)" >&2
    done
    exit 1
  fi
fi
"${as_root[@]}" rm -f "$stamp_file"

root=${AFFINE_ORB_BUILD_ROOT:-build}
build="$root/package"
work=$(mktemp -d /tmp/affine_orb_package.XXXXXX)
chmod 755 "$work"  # apt reads the .deb files as its unprivileged user
brought_in=()  # packages that apt-get install added for ours (their dependencies that were missing)

# Removes the two packages and what their installation brought in; runs on every exit.
cleanup() {
  local status=$?
  set +e
  local remove=()
  for p in "${packages[@]}" "${brought_in[@]}"; do installed "$p" && remove+=("$p"); done
  if ((${#remove[@]})); then
    echo "removing: ${remove[*]}"
    "${as_root[@]}" "${apt_get[@]}" remove -y "${remove[@]}" > "$work/remove.log" 2>&1 || {
      cat "$work/remove.log"
      status=1
    }
  fi
  local left=0
  for p in "${packages[@]}"; do
    if installed "$p"; then
      echo "Debian packages: $p is still installed" >&2
      status=1
      left=1
    fi
  done
  ((left)) || "${as_root[@]}" rm -f "$stamp_file"
  rm -rf "$work"
  exit $status
}
trap cleanup EXIT
trap 'exit 130' INT TERM HUP  # through cleanup too

echo "-- packaging build"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr \
  -DAFFINE_ORB_BUILD_TESTS=OFF -DAFFINE_ORB_BUILD_EXAMPLES=OFF -DAFFINE_ORB_BUILD_BENCH=OFF \
  -DAFFINE_ORB_BUILD_ADAPTERS=OFF -DAFFINE_ORB_BUILD_PYTHON=ON > "$work/configure.log" ||
  { cat "$work/configure.log"; exit 1; }
version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$build/CMakeCache.txt")
cmake --build "$build" -j "$(nproc)"
rm -f "$build"/*.deb
(cd "$build" && cpack -G DEB > "$work/cpack.log") || { cat "$work/cpack.log"; exit 1; }
arch=$(dpkg --print-architecture)
dev="$build/libaffine-orb-dev_${version}_all.deb"
python="$build/python3-affine-orb_${version}_${arch}.deb"
for deb in "$dev" "$python"; do
  [[ -f $deb ]] || { echo "cpack did not write $deb" >&2; ls "$build"/*.deb >&2; exit 1; }
  echo "$(basename "$deb"): $(dpkg-deb -f "$deb" Depends)"
  cp "$deb" "$work/"
done

echo "-- apt-get install"
debs=("$work/$(basename "$dev")" "$work/$(basename "$python")")
mapfile -t brought_in < <("${as_root[@]}" "${apt_get[@]}" install -s --no-install-recommends "${debs[@]}" 2>/dev/null |
  sed -n 's/^Inst \([^ ]*\).*/\1/p' | grep -vxF -e libaffine-orb-dev -e python3-affine-orb || true)
((${#brought_in[@]} == 0)) || echo "also installs (and will remove): ${brought_in[*]}"
{ echo "since $(date +%s)"; for p in "${brought_in[@]}"; do echo "extra $p"; done; } |
  "${as_root[@]}" tee "$stamp_file" > /dev/null
"${as_root[@]}" "${apt_get[@]}" install -y --no-install-recommends "${debs[@]}" > "$work/install.log" 2>&1 || { cat "$work/install.log"; exit 1; }
for p in "${packages[@]}"; do installed "$p" || { echo "$p did not install" >&2; exit 1; }; done
for p in "${packages[@]}"; do echo "time $p $(list_time "$p")"; done | "${as_root[@]}" tee -a "$stamp_file" > /dev/null

echo "-- C++ consumer against /usr (find_package and pkg-config)"
cmake -DPREFIX=/usr -DSOURCE_DIR="$PWD/tests/consumer" -DWORK_DIR="$work/consumer" -DGENERATOR=Ninja \
  -DCXX="$(command -v c++)" -DVERSION="$version" -P tests/consumer/check.cmake

echo "-- Python: /usr/bin/python3 imports the installed module"
module=$(cd /tmp && env -u PYTHONPATH /usr/bin/python3 -I -c \
  'import affine_orb; affine_orb.Extractor(); print(affine_orb.__file__, affine_orb.__version__)')
echo "$module"
read -r file module_version <<< "$module"
[[ $file == /usr/lib/python3/dist-packages/affine_orb.* && $module_version == "$version" ]] ||
  { echo "expected version $version from /usr/lib/python3/dist-packages" >&2; exit 1; }

echo "-- apt-get remove"
"${as_root[@]}" "${apt_get[@]}" remove -y "${packages[@]}" > "$work/remove.log" 2>&1 || { cat "$work/remove.log"; exit 1; }
for path in /usr/include/affine_orb /usr/share/cmake/affine_orb /usr/share/pkgconfig/affine_orb.pc "$file"; do
  [[ ! -e $path ]] || { echo "$path is still there after apt-get remove" >&2; exit 1; }
done
echo "Debian packages: built, installed, used and removed in $((SECONDS - start)) s"
