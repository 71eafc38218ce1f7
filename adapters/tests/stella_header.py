#!/usr/bin/env python3
"""stella_header.py STOCK_HEADER OUT -- writes stella's orb_extractor.h as adapters/stella_vslam/install.sh
leaves it (common/install_stella.py's patched_header()), for test_stella_vslam_adapter, which compiles the
adapter against it."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))
import install_stella  # noqa: E402

if len(sys.argv) != 3:
    sys.exit(__doc__)
out = Path(sys.argv[2])
out.parent.mkdir(parents=True, exist_ok=True)
out.write_bytes(install_stella.patched_header(Path(sys.argv[1]).read_bytes()))
