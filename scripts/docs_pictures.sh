#!/usr/bin/env bash
# Regenerates the docs' pictures (docs/images/): the panels, the samples, Firn next to Real Snow.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
images="$FIRN_ROOT/docs/images"
mkdir -p "$images"
run_blender() {
  BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/docs_config" \
    blender -noaudio --python-exit-code 1 "$@"
}
empty="$(mktemp -d)/empty.blend"
run_blender -b --factory-startup --python-expr "import bpy; bpy.ops.wm.save_as_mainfile(filepath='$empty')"
xvfb-run -a -s "-screen 0 1200x2400x24" \
  env BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/docs_config" \
  blender --factory-startup -noaudio "$empty" --python "$FIRN_ROOT/scripts/screenshot_panels.py" -- "$images/panels.png"
scene="$(dirname "$empty")/viewport.blend"
run_blender -b --factory-startup --python "$FIRN_ROOT/scripts/screenshot_viewport.py" -- build "$scene"
xvfb-run -a -s "-screen 0 1280x800x24" \
  env BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/docs_config" \
  blender --factory-startup -noaudio "$scene" --python "$FIRN_ROOT/scripts/screenshot_viewport.py" -- shoot "$images"
xvfb-run -a -s "-screen 0 1280x800x24" \
  env BLENDER_USER_SCRIPTS="$FIRN_BUILD/blender_scripts" BLENDER_USER_CONFIG="$FIRN_BUILD/docs_config" \
  blender --factory-startup --enable-event-simulate -noaudio --python "$FIRN_ROOT/scripts/screenshot_brush.py" -- "$images"
for sample in car_under_snow teapot_and_ball nishita_comparison firn_vs_real_snow night_street grain_snow grain_scales grain_cube fresh_snow_glints wheel_rut; do
  run_blender -b --factory-startup --python "$FIRN_ROOT/blend_samples/$sample.py" -- --output "$images/$sample.png" --no-save
done
# The skier's animation (36 frames at 160 px); its 24th frame is the docs' picture.
run_blender -b --factory-startup --python "$FIRN_ROOT/blend_samples/skier.py" -- --output "$(dirname "$empty")/skier/" --no-save
cp "$(dirname "$empty")/skier/0024.png" "$images/skier.png"
# The headlights' drive (8 frames at 320 px, Bake Light Sequence); its first, middle and last frames side by side.
run_blender -b --factory-startup --python "$FIRN_ROOT/blend_samples/headlights.py" -- \
  --output "$(dirname "$empty")/headlights.png" --no-save
cp "$(dirname "$empty")/headlights.png" "$images/headlights.png"
# Grain snow from the core alone (no Blender): Chrisman's accumulation and the brute-force grain renderer.
PYTHONPATH="$FIRN_BUILD/python" /usr/bin/python3 "$FIRN_ROOT/scripts/grains_picture.py" "$images/grains_red_ball.png" \
  --width 320 --samples 32 --grains 150000
echo "firn: pictures in $images"
