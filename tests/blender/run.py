"""Runs the add-on tests with pytest inside Blender: blender -b --python run.py -- TEST_DIR [pytest args].

Blender (Debian) runs the system Python, so Debian's python3-pytest is importable here.
The exit code is pytest's, so CTest sees failures.
"""

import sys

import addon_utils
import pytest

argv = sys.argv[sys.argv.index("--") + 1:]
addon_utils.enable("firn", default_set=True, handle_error=None)
if "firn" not in {m.__name__ for m in addon_utils.modules() if addon_utils.check(m.__name__)[1]}:
    print("firn add-on could not be enabled", file=sys.stderr)
    sys.exit(2)
sys.exit(int(pytest.main(["-q", "-rs", "-p", "no:cacheprovider", *argv])))
