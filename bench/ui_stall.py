"""How long Blender's UI stalls during Add Snow Layer and Bake Scattering on the car sample, as a user runs them.

bench/ui_stall.sh runs it twice: in the background it builds the car scene and saves it (blender -b ... -- SCENE),
then in a window (xvfb-run) it opens that scene and measures (blender SCENE ...).

A timer ticks every 10 ms on the main thread; a stall is the longest gap between two ticks. Each operator is
measured in three phases: its invoke (main thread: reads the scene before the worker starts), the worker
(main thread free: the timer should keep ticking), and the end (main thread: the result written into Blender,
up to the first tick after the job). Goal: <= 0.1 s while the worker runs. Timings vary with the machine's load.
"""

import os
import sys
import time
import traceback

import addon_utils
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "blender_ui"))
import car_under_snow  # noqa: E402
from ui_test import job_running, window_context  # noqa: E402

TICK = 0.01  # s
state = {"phase": "start", "last": 0.0, "rows": []}


class Stalls:
    """Longest gap between timer ticks, per phase of one operator."""

    def __init__(self, name):
        self.name, self.invoke, self.worker, self.end, self.ticks = name, 0.0, 0.0, 0.0, 0
        self.seconds = 0.0

    def row(self):
        return (f"| {self.name} | {self.invoke:.3f} | {self.worker:.3f} | {self.end:.3f} | {self.ticks} "
                f"| {self.seconds:.1f} |")


def start(name, operator, **props):
    stalls = Stalls(name)
    began = time.perf_counter()
    with bpy.context.temp_override(**window_context()):
        result = operator("INVOKE_DEFAULT", **props)
    now = time.perf_counter()
    if result != {"RUNNING_MODAL"}:
        raise RuntimeError(f"{name}: {result}")
    stalls.invoke, stalls.began = now - began, began
    state["last"], state["job"], state["ended"] = now, stalls, False
    return stalls


def measure(now):
    """Called on each tick while an operator runs; True once its job and its end are measured."""
    stalls, gap = state["job"], now - state["last"]
    if state["ended"]:  # first tick after the job's thread ended: the gap spans the operator's end
        stalls.end = max(stalls.end, gap)
        stalls.seconds = now - stalls.began
        state["rows"].append(stalls.row())
        return True
    if job_running():
        stalls.worker, stalls.ticks = max(stalls.worker, gap), stalls.ticks + 1
    else:
        state["ended"] = True
    return False


def tick():
    try:
        now = time.perf_counter()
        phase = state["phase"]
        if phase == "start":
            addon_utils.enable("firn", default_set=True)
            targets = [obj for obj in bpy.data.objects if obj.type == "MESH"]
            bpy.ops.object.select_all(action="DESELECT")
            for obj in targets:
                obj.select_set(True)
            bpy.context.view_layer.objects.active = targets[0]
            start("Add Snow Layer", bpy.ops.firn.add_snow_layer, depth=0.12, spacing=0.06, voxel_size=0.02)
            state["phase"] = "snow"
        elif phase == "snow" and measure(now):
            snow = bpy.context.active_object
            bpy.ops.object.select_all(action="DESELECT")
            snow.select_set(True)
            start("Bake Scattering (Final)", bpy.ops.firn.bake_scattering, quality="FINAL")
            state["phase"] = "bake"
        elif phase == "bake" and measure(now):
            print("| operator | invoke (s) | longest stall while the worker runs (s) | end (s) | ticks | total (s) |")
            print("|---|---|---|---|---|---|")
            print("\n".join(state["rows"]), flush=True)
            bpy.ops.wm.quit_blender()
            return None
        state["last"] = time.perf_counter()
    except Exception:
        traceback.print_exc()
        os._exit(1)
    return TICK


if bpy.app.background:  # first run: build the scene once, save it where the shell script says
    car_under_snow.build_scene()
    bpy.ops.wm.save_as_mainfile(filepath=sys.argv[sys.argv.index("--") + 1])
else:
    bpy.app.timers.register(tick, first_interval=1.0)
