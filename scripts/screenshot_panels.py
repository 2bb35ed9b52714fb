"""Screenshot of Firn's panels for the docs: Blender with a window under Xvfb.

xvfb-run -s "-screen 0 1200x2400x24" blender --factory-startup EMPTY.blend --python scripts/screenshot_panels.py -- OUT.png
(scripts/docs_pictures.sh runs it with the add-on from the build tree; opening a .blend skips the splash.)
The 3D viewport's area shows a Properties editor on the snow object, with Firn's panels.
"""

import os
import sys

import addon_utils
import bpy

output = os.path.abspath(sys.argv[sys.argv.index("--") + 1])


def build():
    addon_utils.enable("firn", default_set=True)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    ground = bpy.context.object
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.0, 0.0, 0.75), scale=(0.8, 0.6, 0.05))
    bpy.ops.object.select_all(action="DESELECT")
    ground.select_set(True)
    bpy.context.view_layer.objects.active = ground
    bpy.ops.firn.add_snow_layer(depth=0.1)


def big_properties_editor():
    for area in bpy.context.window_manager.windows[0].screen.areas:
        if area.type == "VIEW_3D":
            area.type = "PROPERTIES"


def object_tab():
    window = bpy.context.window_manager.windows[0]
    for area in window.screen.areas:
        if area.type == "PROPERTIES":
            area.spaces.active.context = "OBJECT"


def shoot():
    window = bpy.context.window_manager.windows[0]
    with bpy.context.temp_override(window=window):
        bpy.ops.screen.screenshot(filepath=output)
    print("wrote", output)
    bpy.ops.wm.quit_blender()


def step():
    step.stage += 1
    if step.stage == 1:
        build()
        big_properties_editor()
        return 0.5
    if step.stage == 2:  # the new editor has its tabs once it was drawn
        object_tab()
        return 1.0
    shoot()
    return None


step.stage = 0
bpy.app.timers.register(step, first_interval=1.0)
