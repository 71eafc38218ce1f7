# shellcheck shell=bash
# debian_packages.sh -- sourced by the scripts of bench/slam: install_missing PACKAGE... installs
# with apt-get the Debian packages that are not installed yet (as root; otherwise it names them and
# exits 1).
install_missing() {
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || missing+=("$p")
  done
  [ ${#missing[@]} -gt 0 ] || return 0
  echo "== $(date -u +%T) apt-get install ${missing[*]}"
  [ "$(id -u)" = 0 ] || { echo "run as root, or install first: ${missing[*]}" >&2; exit 1; }
  apt-get install -y --no-install-recommends "${missing[@]}"
}
