#!/bin/sh
# Installs this adapter into a stella_vslam checkout, or removes it: install.sh [--uninstall] STELLA_DIR
# (--help says more). The work is done by ../common/install_stella.py.
exec python3 "$(dirname "$0")/../common/install_stella.py" "$@"
