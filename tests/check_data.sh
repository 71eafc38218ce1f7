#!/usr/bin/env bash
# Checks the evaluation data against docs/data.sha256 (one SHA-256 per file; docs/data.md names the
# sources): every listed file must be there with its checksum.
#   bash tests/check_data.sh [DATA_DIR]      (default: ../shared/data beside the checkout)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
data=${1:-$root/../shared/data}
if [[ ! -d $data ]]; then
  echo "no evaluation data at $data (docs/data.md says where it comes from)" >&2
  exit 1
fi
cd "$data"
sha256sum --check --quiet --strict "$root/docs/data.sha256"
echo "$(wc -l < "$root/docs/data.sha256") files in $data match docs/data.sha256"
