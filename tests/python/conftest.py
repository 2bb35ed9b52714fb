import os

import pytest


@pytest.fixture
def tmp_vdb(tmp_path):
    """A path for a VDB file in a fresh temporary folder."""
    return os.fspath(tmp_path / "snow.vdb")
