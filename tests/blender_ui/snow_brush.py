"""Blender with a window (under xvfb-run): the Snow Brush as a user paints with it (issue 15). Started from the Firn
panel's button (INVOKE_DEFAULT), a drag adds snow under the mouse, Ctrl+drag erases it, each stroke is its own undo
step, Esc ends the brush.

xvfb-run blender --factory-startup --enable-event-simulate --python snow_brush.py   (exit code 0 = pass)
"""

import os
import sys
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import aim_view, fail, passed, plane_alone, press_esc, window_context  # noqa: E402

state = {"phase": "start", "events": []}
ABOVE_OLD_TOP = (0.0, 0.0, 0.14)  # m: above the 0.1 m layer, under the painted snow


def setup():
    press_esc()  # closes the splash screen, as a user would
    plane_alone(4.0)
    if bpy.ops.firn.add_snow_layer(depth=0.1) != {"FINISHED"}:
        fail("Add Snow Layer did not finish")
    context = window_context()
    aim_view(context["area"].spaces.active, (0.0, 0.0, 0.0), 0.0, 0.0, 6.0)  # straight down on the snow
    context["area"].tag_redraw()


def snow():
    return next(obj for obj in bpy.data.objects if obj.firn.is_snow)


def density_above_old_top():
    from firn.common.core import firncore

    return float(firncore.sample_grid(bpy.path.abspath(snow().data.filepath), "density",
                                      np.array([ABOVE_OLD_TOP], np.float32))[0])


def drag(ctrl=False):
    """Events of a short drag through the view's centre (window pixels), pressed and released."""
    region = window_context()["region"]
    cx, cy = region.x + region.width // 2, region.y + region.height // 2
    path = [(cx - 20 + 4 * i, cy) for i in range(11)]
    events = [("MOUSEMOVE", "NOTHING", path[0])] + [("LEFTMOUSE", "PRESS", path[0])]
    events += [("MOUSEMOVE", "NOTHING", point) for point in path[1:]] + [("LEFTMOUSE", "RELEASE", path[-1])]
    return [(kind, value, point, ctrl) for kind, value, point in events]


def send(event):
    kind, value, (x, y), ctrl = event
    bpy.context.window_manager.windows[0].event_simulate(type=kind, value=value, x=x, y=y, ctrl=ctrl)


def tick():
    try:
        phase = state["phase"]
        if state["events"]:  # one event a tick: the brush handles each as a user's would be
            send(state["events"].pop(0))
            return 0.05
        if phase == "start":
            setup()
            state["phase"] = "invoke"
        elif phase == "invoke":
            state["balls"], state["file"] = len(snow().firn.metaballs.data.vertices), snow().data.filepath
            if density_above_old_top() != 0.0:
                fail("snow above the layer's top before painting")
            with bpy.context.temp_override(**window_context()):
                result = bpy.ops.firn.snow_brush("INVOKE_DEFAULT", radius=0.3, strength=0.05)
            if result != {"RUNNING_MODAL"}:
                fail(f"expected RUNNING_MODAL, got {result}")
            state["events"], state["phase"] = drag(), "painted"
        elif phase == "painted":
            painted = density_above_old_top()
            if len(snow().firn.metaballs.data.vertices) <= state["balls"] or painted <= 50.0:
                fail(f"the drag added no snow under the mouse (density {painted:.0f} kg/m³)")
            if snow().data.filepath == state["file"]:
                fail("the stroke did not write a new file (undo would lose it)")
            print(f"drag added {len(snow().firn.metaballs.data.vertices) - state['balls']} metaballs, "
                  f"{painted:.0f} kg/m³ above the old top", flush=True)
            state["painted_file"] = snow().data.filepath
            state["events"], state["phase"] = drag(ctrl=True), "erased"
        elif phase == "erased":
            if density_above_old_top() >= 1.0:
                fail("Ctrl+drag did not erase the painted snow")
            send(("ESC", "PRESS", (0, 0), False))
            state["phase"] = "ended"
        elif phase == "ended":
            if any(op.bl_idname == "FIRN_OT_snow_brush" for op in bpy.context.window_manager.operators[-1:]):
                fail("the brush registered itself as a redoable operator: its strokes are the undo steps")
            send(("Z", "PRESS", (0, 0), True))  # Ctrl+Z: the erase stroke is undone, the painted snow is back
            send(("Z", "RELEASE", (0, 0), True))
            state["phase"] = "undone"
        elif phase == "undone":
            if snow().data.filepath != state["painted_file"] or density_above_old_top() <= 50.0:
                fail(f"Ctrl+Z did not give back the snow before the erase stroke ({snow().data.filepath})")
            passed()
            return None
        window_context()["area"].tag_redraw()
    except Exception:
        traceback.print_exc()
        fail("exception in the UI test")
    return 0.3


bpy.app.timers.register(tick, first_interval=1.0)
