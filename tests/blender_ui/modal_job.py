"""Blender with a window (under xvfb-run): Add Snow Layer started as a user would (INVOKE_DEFAULT) runs in a
worker thread, the UI keeps running meanwhile, Esc-style cancel leaves the scene unchanged.

xvfb-run blender --factory-startup --enable-event-simulate --python modal_job.py   (exit code 0 = pass)
"""

import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import (  # noqa: E402
    HUNG, fail, gate_worker, job_running, passed, plane_alone, press_esc, run_timer, ui_tick, window_context,
    worker_alive)

state = {"ticks": 0, "phase": "start", "started": 0.0, "while_computing": 0}


def setup():
    from firn.snow_layer.operators import FIRN_OT_add_snow_layer

    ground = plane_alone(4.0)
    gate_worker(FIRN_OT_add_snow_layer)  # its worker computes only once the UI has run beside it
    ground.select_set(True)
    bpy.context.view_layer.objects.active = ground


def start_job():
    with bpy.context.temp_override(**window_context()):
        result = bpy.ops.firn.add_snow_layer("INVOKE_DEFAULT", depth=0.1, spacing=0.02)
    if result != {"RUNNING_MODAL"}:
        fail(f"expected RUNNING_MODAL, got {result}")
    if not worker_alive():  # the operator returned to the UI while its worker thread computes
        fail("the job did not run in a worker thread")
    state["started"] = time.perf_counter()
    state["while_computing"] = 0


def snow_objects():
    return [obj for obj in bpy.data.objects if obj.firn.is_snow]


def step():
    state["ticks"] += 1
    state["while_computing"] += worker_alive()
    ui_tick()
    if state["phase"] == "start":
        setup()
        start_job()
        state["phase"] = "running"
        state["ticks"] = 0
    elif state["phase"] == "running":
        if snow_objects():
            # The UI (this timer) ran while the worker computed (gate_worker); how often depends on the load.
            print(f"modal job finished after {time.perf_counter() - state['started']:.2f} s with "
                  f"{state['while_computing']} UI ticks while it computed")
            state["phase"] = "cancel"
            bpy.ops.mesh.primitive_plane_add(size=12.0, location=(50, 0, 0))
            start_job()
            state["ticks"] = 0
        elif time.perf_counter() - state["started"] > HUNG:
            fail("modal job hung")
    elif state["phase"] == "cancel":
        if state["ticks"] == 4:  # the job is under way: press Esc as a user would
            if not job_running():
                fail("the second job ended before Esc could be tested")
            press_esc()
            state["phase"] = "cancelled"
            state["started"] = time.perf_counter()
    elif state["phase"] == "cancelled":
        if not job_running():
            print(f"Esc stopped the job in {time.perf_counter() - state['started']:.2f} s")
            if len(snow_objects()) != 1:
                fail(f"Esc left {len(snow_objects())} snow objects, expected the first one only")
            passed()
            return False
        if time.perf_counter() - state["started"] > HUNG:
            fail("Esc did not stop the job: hung")


run_timer(step)
