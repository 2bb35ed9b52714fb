"""The user guide's pictures of masks and the Snow Brush (docs/images/snow_masks.png, snow_brush.png), in Solid
shading with the viewport proxy. Run by scripts/docs_pictures.sh:

  xvfb-run -s "-screen 0 1280x800x24" blender --factory-startup --enable-event-simulate --python screenshot_brush.py
      -- IMAGES_FOLDER

Masks: a grid with its left half's faces selected next to one whose vertex group fades from 1 to 0 across it.
Brush: a floor under a table, a drift painted along an S (no snow lands under the table), a path erased across it,
and the brush's circle under the mouse while the brush runs.
"""

import math
import os
import sys
import traceback

import addon_utils
import bpy
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "blender_ui"))
from ui_test import aim_view, window_context  # noqa: E402

FOLDER = sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else "."
state = {"phase": "start", "wait": 0}


def clear():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)


def select_only(*objects):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = objects[0]


def masks_scene():
    clear()
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=20, y_subdivisions=20, size=2.0, location=(-1.2, 0, 0))
    selected = bpy.context.object
    for polygon in selected.data.polygons:
        polygon.select = polygon.center.x < 0.0
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=20, y_subdivisions=20, size=2.0, location=(1.2, 0, 0))
    faded = bpy.context.object
    group = faded.vertex_groups.new(name="Snow")
    for vertex in faded.data.vertices:
        group.add([vertex.index], float(np.clip(0.5 - 0.5 * vertex.co.x, 0.0, 1.0)), "REPLACE")
    select_only(selected)
    bpy.ops.firn.add_snow_layer(depth=0.15, only_selected_faces=True)
    select_only(faded)
    bpy.ops.firn.add_snow_layer(depth=0.2, vertex_group="Snow")
    look((0.0, 0.0, 0.0), 72.0, 0.0, 6.0)


def stroke_points(points):
    return [{"name": "", "location": p, "mouse": (0, 0), "mouse_event": (0, 0), "pressure": 1.0, "size": 0,
             "pen_flip": False, "time": 0.0, "is_start": i == 0, "x_tilt": 0.0, "y_tilt": 0.0}
            for i, p in enumerate(points)]


def brush_scene():
    clear()
    bpy.ops.mesh.primitive_plane_add(size=5.0)
    floor = bpy.context.object
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.8, 0.6, 0.8), scale=(1.2, 1.0, 0.05))
    select_only(floor)
    bpy.ops.firn.add_snow_layer(depth=0.05)
    s_curve = [(1.6 * math.sin(t), -1.6 + 3.2 * t / math.pi, 0.05) for t in np.linspace(0.0, math.pi, 40)]
    for _ in range(4):
        bpy.ops.firn.snow_brush(stroke=stroke_points(s_curve), mode="ADD", radius=0.35, strength=0.04)
    erase = [(x, -0.9, 0.1) for x in np.linspace(-2.2, 2.2, 30)]
    bpy.ops.firn.snow_brush(stroke=stroke_points(erase), mode="ERASE", radius=0.2, strength=0.5)
    look((0.0, 0.0, 0.0), 50.0, -25.0, 7.5)


def look(location, pitch, yaw, distance):
    context = window_context()
    space = context["area"].spaces.active
    space.shading.type = "SOLID"
    space.overlay.show_overlays = False
    aim_view(space, location, pitch, yaw, distance)
    context["area"].tag_redraw()


def shoot(name):
    context = window_context()
    with bpy.context.temp_override(**context):
        bpy.ops.screen.screenshot_area(filepath=os.path.join(FOLDER, name))
    print("wrote", os.path.join(FOLDER, name), flush=True)


def start_brush():
    """The modal brush, with the mouse over the drift: its circle shows where it would paint."""
    with bpy.context.temp_override(**window_context()):
        bpy.ops.firn.snow_brush("INVOKE_DEFAULT", radius=0.35, strength=0.04)
    region = window_context()["region"]
    x, y = region.x + int(region.width * 0.47), region.y + int(region.height * 0.42)
    bpy.context.window_manager.windows[0].event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)


def tick():
    try:
        if state["wait"] > 0:
            state["wait"] -= 1
            window_context()["area"].tag_redraw()
            return 0.5
        phase = state["phase"]
        if phase == "start":
            window = bpy.context.window_manager.windows[0]
            window.event_simulate(type="ESC", value="PRESS")  # the splash screen
            window.event_simulate(type="ESC", value="RELEASE")
            addon_utils.enable("firn", default_set=True)
            masks_scene()
            state["phase"], state["wait"] = "masks", 4
        elif phase == "masks":
            shoot("snow_masks.png")
            brush_scene()
            state["phase"], state["wait"] = "brush", 2
        elif phase == "brush":
            start_brush()
            state["phase"], state["wait"] = "circle", 4
        elif phase == "circle":
            window_context()["area"].spaces.active.overlay.show_overlays = True  # the brush circle is an overlay
            state["phase"], state["wait"] = "shoot", 3
        elif phase == "shoot":
            shoot("snow_brush.png")
            bpy.ops.wm.quit_blender()
            return None
    except Exception:
        traceback.print_exc()
        os._exit(1)
    return 0.5


bpy.app.timers.register(tick, first_interval=1.0)
