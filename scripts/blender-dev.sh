#!/usr/bin/env bash
# Developer mode: Blender with the add-on straight from the build tree (Python sources live, no install).
# Rebuild (scripts/setup.sh) after C++ changes. Arguments go to Blender, e.g. scripts/blender-dev.sh -b file.blend
set -euo pipefail
FIRN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FIRN_BUILD="${FIRN_BUILD:-$FIRN_ROOT/build}"
[ -d "$FIRN_BUILD/blender_scripts/addons/firn" ] || { echo "build first: scripts/setup.sh" >&2; exit 1; }
BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" exec blender --addons firn "$@"
