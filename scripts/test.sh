#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test (C++, python3 core, Blender add-on).
# Extra arguments go to ctest, e.g. scripts/test.sh -L cpp  or  scripts/test.sh -R snow. The tests run on every core
# (tests/CMakeLists.txt keeps apart those that share a resource).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$FIRN_BUILD"
ctest --output-on-failure --parallel "$(nproc)" "$@"
