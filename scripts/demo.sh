#!/usr/bin/env bash
# The README's main command: installs what is missing, builds the add-on (not the tests), then builds the car
# sample scene, adds snow, bakes the light in it and renders it with Cycles to out/demo.png, printing the time
# of each stage. The scene is saved as out/demo.blend (its snow in out/firn_cache/) to open in Blender.
set -euo pipefail
FIRN_BUILD_TARGETS=firn_addon
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
out="$FIRN_ROOT/out"
mkdir -p "$out"
BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/demo_config" \
  blender -b --factory-startup -noaudio --python-exit-code 1 \
  --python "$FIRN_ROOT/blend_samples/car_under_snow.py" -- --output "$out/demo.png" --blend "$out/demo.blend" "$@"
cat <<DONE

firn: the picture is $out/demo.png
firn: the scene is $out/demo.blend; open it in Blender with Firn from this build:
        $FIRN_ROOT/scripts/blender-dev.sh $out/demo.blend
      (or install $(ls "$FIRN_BUILD"/firn-*-linux-x86_64.zip) in Blender: Edit > Preferences > Add-ons > Install)
DONE
