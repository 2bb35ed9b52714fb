#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, then builds the car sample scene, adds snow,
# bakes the light in it and renders it with Cycles to out/demo.png, printing the time of each stage.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
mkdir -p "$FIRN_ROOT/out"
BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/demo_config" \
  blender -b --factory-startup -noaudio --python-exit-code 1 \
  --python "$FIRN_ROOT/blend_samples/car_under_snow.py" -- --output "$FIRN_ROOT/out/demo.png" --no-save "$@"
echo "firn: wrote $FIRN_ROOT/out/demo.png"
