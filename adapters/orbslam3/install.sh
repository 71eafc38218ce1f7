#!/bin/sh
# Installs this adapter into an ORB-SLAM3 checkout, or removes it: install.sh [--uninstall] FORK_DIR
# (--help says more). The work is done by ../common/install_adapter.py, shared with the other fork.
exec python3 "$(dirname "$0")/../common/install_adapter.py" orbslam3 "$@"
