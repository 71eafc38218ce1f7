"""The pytest marker "data": a test that reads the evaluation data (AFFINE_ORB_DATA_DIR: Oxford
sequences; docs/data.md). ctest runs the module's tests twice (adapters/python/CMakeLists.txt):
test_python without the marked tests, test_python_data only them with AFFINE_ORB_NEEDS_DATA=1, which
exits with code 77 (ctest's skip) naming what is missing when the data is not there."""
import os

import pytest

DATA = os.environ.get("AFFINE_ORB_DATA_DIR", os.path.join(os.path.dirname(__file__), "../../../shared/data"))


def pytest_configure(config):
    config.addinivalue_line("markers", "data: reads the evaluation data (AFFINE_ORB_DATA_DIR; docs/data.md)")


def pytest_sessionstart(session):
    if os.environ.get("AFFINE_ORB_NEEDS_DATA") == "1":
        missing = os.path.join(DATA, "oxford")
        if not os.path.isdir(missing):
            pytest.exit("SKIPPED: the evaluation data is missing: %s (configure with -DAFFINE_ORB_DATA_DIR=<dir>; "
                        "docs/data.md says where it comes from)" % missing, returncode=77)
