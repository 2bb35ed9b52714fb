"""The user guide's pictures of the viewport: a plane and the default cube under snow, in Solid, Material Preview
and Rendered shading (docs/images/viewport_*.png). Run by scripts/docs_pictures.sh in two steps:

  blender -b --factory-startup --python screenshot_viewport.py -- build SCENE.blend    (scene, snow, bake)
  xvfb-run blender --factory-startup SCENE.blend --python screenshot_viewport.py -- shoot IMAGES_FOLDER

Each shading mode is shot once the viewport has stopped changing (EEVEE compiles its shaders, Cycles refines its
samples), with a hang guard.
"""

import math
import os
import sys
import time
import traceback

import addon_utils
import bpy
import numpy as np
from mathutils import Euler

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "blender_ui"))
from ui_test import aim_view, window_context  # noqa: E402

MODES = ("SOLID", "MATERIAL", "RENDERED")
SETTLE_CHECK = 2.0  # s between two screenshots that must be the same for the view to count as settled
GIVE_UP = 600.0  # s per mode


def build(path):
    addon_utils.enable("firn", default_set=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=6.0)
    ground = bpy.context.object
    cube = bpy.data.objects["Cube"]
    sun = bpy.data.objects["Light"]
    sun.data.type, sun.data.energy = "SUN", 4.0  # W/m²
    sun.rotation_euler = Euler((math.radians(50.0), 0.0, math.radians(30.0)))
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.4, 0.55, 0.8, 1.0)
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
    scene.cycles.use_denoising, scene.cycles.preview_samples = False, 32
    scene.cycles.sample_clamp_indirect = 0.0  # baked snow is brighter than the default clamp
    bpy.ops.object.select_all(action="DESELECT")
    for obj in (ground, cube):
        obj.select_set(True)
    bpy.context.view_layer.objects.active = ground
    if bpy.ops.firn.add_snow_layer(depth=0.15) != {"FINISHED"}:
        raise RuntimeError("Add Snow Layer failed")
    snow = bpy.context.object
    bpy.ops.object.select_all(action="DESELECT")
    snow.select_set(True)
    bpy.context.view_layer.objects.active = snow
    if bpy.ops.firn.bake_scattering(quality="FINAL") != {"FINISHED"}:
        raise RuntimeError("Bake Scattering failed")
    bpy.ops.object.select_all(action="DESELECT")
    bpy.ops.wm.save_as_mainfile(filepath=path)


def view3d():
    context = window_context()  # the UI tests' override for the first window's 3D viewport
    return context, context["area"].spaces.active


def frame_view():
    context, space = view3d()
    space.overlay.show_overlays = False
    space.show_gizmo = False
    space.shading.use_scene_world_render = True
    aim_view(space, (0.0, 0.0, 0.5), 62.0, 40.0, 9.0)
    context["area"].tag_redraw()


def screenshot(path):
    context, _space = view3d()
    with bpy.context.temp_override(**context):
        bpy.ops.screen.screenshot_area(filepath=path)
    image = bpy.data.images.load(path, check_existing=False)
    pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels


def shoot(folder):
    state = {"modes": list(MODES), "last": None, "since": 0.0, "begun": time.perf_counter()}

    def tick():
        try:
            if state["last"] is None and state["since"] == 0.0:
                frame_view()
                view3d()[1].shading.type = state["modes"][0]
                state["since"] = time.perf_counter()
                return SETTLE_CHECK
            mode = state["modes"][0]
            path = os.path.join(folder, f"viewport_{mode.lower()}.png")
            pixels = screenshot(path)
            settled = state["last"] is not None and np.array_equal(pixels, state["last"])
            if not settled and time.perf_counter() - state["since"] < GIVE_UP:
                state["last"] = pixels
                view3d()[0]["area"].tag_redraw()
                return SETTLE_CHECK
            print(f"firn: {path} ({'settled' if settled else 'NOT settled'} after "
                  f"{time.perf_counter() - state['since']:.0f} s)", flush=True)
            state["modes"].pop(0)
            if not state["modes"]:
                bpy.ops.wm.quit_blender()
                return None
            view3d()[1].shading.type = state["modes"][0]
            state["last"], state["since"] = None, time.perf_counter()
            return SETTLE_CHECK
        except Exception:
            traceback.print_exc()
            os._exit(1)

    addon_utils.enable("firn", default_set=True)
    bpy.app.timers.register(tick, first_interval=1.0)


if __name__ == "__main__":
    command, target = sys.argv[sys.argv.index("--") + 1:][:2]
    if command == "build":
        build(target)
    else:
        shoot(target)
