#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, then renders the demo scene headless to out/demo.png.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
mkdir -p "$FIRN_ROOT/out"
BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/demo_config" \
  blender -b --factory-startup -noaudio --python-exit-code 1 \
  --python "$FIRN_ROOT/blend_samples/demo.py" -- --output "$FIRN_ROOT/out/demo.png"
echo "firn: wrote $FIRN_ROOT/out/demo.png"
