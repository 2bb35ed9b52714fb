"""Blender with a window (under xvfb-run): the snow's viewport proxy makes the snow visible in Solid and in
Material Preview (issue 17). Screenshots of the 3D viewport with the snow shown and hidden: the pixels the snow
covers must be brighter with it than the ground beneath them is without it.

xvfb-run blender --factory-startup --enable-event-simulate --python viewport_proxy.py   (exit code 0 = pass)
"""

import os
import sys
import tempfile
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import HUNG, aim_view, fail, passed, plane_alone, press_esc, run_timer, window_context  # noqa: E402

GROUND = (0.3, 0.3, 0.3, 1.0)  # a mid-grey ground: white snow on it must stand out
MIN_SNOW_PIXELS = 2000  # the snow covers a quarter of the view (about 100k pixels): far more than this
state = {"phase": "start", "ticks": 0, "started": 0.0, "folder": tempfile.mkdtemp(prefix="firn_ui_proxy_")}


def view3d():
    context = window_context()
    return context, context["area"].spaces.active


def setup():
    press_esc()  # closes the splash screen, as a user would
    ground = plane_alone(4.0)
    material = bpy.data.materials.new("Ground")
    material.diffuse_color = GROUND
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = GROUND
    ground.data.materials.append(material)
    bpy.ops.object.select_all(action="DESELECT")
    ground.select_set(True)
    bpy.context.view_layer.objects.active = ground
    if bpy.ops.firn.add_snow_layer(depth=0.1, spacing=0.05) != {"FINISHED"}:
        fail("Add Snow Layer did not finish")
    context, space = view3d()
    space.overlay.show_overlays = False  # no grid, no outlines: the pixels are the shaded scene's
    aim_view(space, (0.0, 0.0, 0.0), 55.0, 30.0, 5.0)
    context["area"].tag_redraw()


def snow_objects():
    return [obj for obj in bpy.data.objects if obj.firn.is_snow or obj.firn.is_proxy]


def show_snow(shown):
    for obj in snow_objects():
        obj.hide_set(not shown)


def screenshot(name):
    context, _space = view3d()
    path = os.path.join(state["folder"], f"{name}.png")
    with bpy.context.temp_override(**context):
        bpy.ops.screen.screenshot_area(filepath=path)
    image = bpy.data.images.load(path)
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    rgba = pixels.reshape(height, width, 4)
    return rgba[..., :3].mean(axis=-1)  # brightness per pixel


def snow_is_visible(with_snow, without_snow, mode):
    """The pixels the snow changes, and whether they are brighter than the ground under them."""
    covered = np.abs(with_snow - without_snow) > 0.02
    count = int(covered.sum())
    if count < MIN_SNOW_PIXELS:
        return False, f"{mode}: the snow changes only {count} pixels"
    snow, beneath = float(with_snow[covered].mean()), float(without_snow[covered].mean())
    message = f"{mode}: {count} snow pixels, mean brightness {snow:.3f} against {beneath:.3f} beneath"
    return snow > beneath + 0.1, message


def step():
    """Phases per shading mode: set the mode, shot with the snow, shot without; repeat until the snow shows
    (EEVEE compiles its shaders in the background first) or the hang guard fires."""
    state["ticks"] += 1
    phase = state["phase"]
    if phase == "start":
        setup()
        state["modes"] = ["SOLID", "MATERIAL"]
        state["phase"] = "mode"
    elif phase == "mode":
        _context, space = view3d()
        space.shading.type = state["modes"][0]
        state["started"], state["phase"] = time.perf_counter(), "with"
        show_snow(True)
    elif phase == "with":
        state["with"] = screenshot(f"{state['modes'][0].lower()}_snow")
        show_snow(False)
        state["phase"] = "without"
    elif phase == "without":
        without = screenshot(f"{state['modes'][0].lower()}_ground")
        show_snow(True)
        visible, message = snow_is_visible(state["with"], without, state["modes"][0])
        if visible:
            print(message, flush=True)
            state["modes"].pop(0)
            state["phase"] = "mode" if state["modes"] else "done"
        elif time.perf_counter() - state["started"] > HUNG:
            fail(message)
        else:
            state["phase"] = "with"  # shaders still compiling: look again
    elif phase == "done":
        passed(f"PASS: screenshots in {state['folder']}")
        return False
    view3d()[0]["area"].tag_redraw()


run_timer(step, interval=0.5, first_interval=1.0)
