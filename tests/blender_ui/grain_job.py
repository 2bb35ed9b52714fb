"""Blender with a window (under xvfb-run): Add Grain Snow started as a user would (INVOKE_DEFAULT) accumulates in
a worker thread with progress, and Esc cancels it leaving the scene as it was (no object, Cycles' light paths
untouched).

xvfb-run blender --factory-startup --enable-event-simulate --python grain_job.py   (exit code 0 = pass)
"""

import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import (HUNG, esc_once_progressing, fail, job_running, passed, plane_alone, run_timer,  # noqa: E402
                     start_modal)

GRAINS = 2_000_000  # seconds of accumulation on any machine: long enough to be cancelled half way
state = {"phase": "start", "started": 0.0, "bounces": 0}


def start_job():
    plane_alone(1.0).select_set(True)
    state["bounces"] = bpy.context.scene.cycles.max_bounces
    start_modal(state, lambda: bpy.ops.firn.add_grain_snow("INVOKE_DEFAULT", grain_radius=0.001, grain_count=GRAINS))


def step():
    if state["phase"] == "start":
        start_job()
        state["phase"] = "running"
    elif state["phase"] == "running":
        esc_once_progressing(state, "raise GRAINS")
    elif state["phase"] == "cancelled":
        if not job_running():
            print(f"Esc stopped Add Grain Snow in {time.perf_counter() - state['started']:.2f} s")
            if any(obj.firn.is_grains for obj in bpy.data.objects):
                fail("Esc left a grain object")
            if bpy.context.scene.cycles.max_bounces != state["bounces"]:
                fail("a cancelled Add Grain Snow changed Cycles' light paths")
            passed()
            return False
        if time.perf_counter() - state["started"] > HUNG:
            fail("Esc did not stop the job: hung")
    return True


run_timer(step)
