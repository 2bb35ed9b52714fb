#!/usr/bin/env bash
# The UI's longest stalls during Add Snow Layer and Bake Scattering on the car sample, in a real window (Xvfb).
# Usage: bench/ui_stall.sh [--world rendered]   (default: the car's Nishita world, computed by the core)
set -euo pipefail
FIRN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
FIRN_BUILD="${FIRN_BUILD:-$FIRN_ROOT/build}"
scene="$FIRN_BUILD/bench_ui_stall_car.blend"
export BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/bench_ui_config"
blender -b --factory-startup -noaudio --python-exit-code 1 --python "$FIRN_ROOT/bench/ui_stall.py" -- "$scene" >/dev/null
xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup -noaudio "$scene" \
  --python "$FIRN_ROOT/bench/ui_stall.py" -- "$@" 2>&1 | grep "^|" || true
