"""Blender with a window (under xvfb-run): Add Grain Snow started as a user would (INVOKE_DEFAULT) accumulates in
a worker thread with progress, and Esc cancels it leaving the scene as it was (no object, Cycles' light paths
untouched).

xvfb-run blender --factory-startup --enable-event-simulate --python grain_job.py   (exit code 0 = pass)
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import fail, plane_alone, run_cancel_test, start_modal  # noqa: E402

GRAINS = 2_000_000  # seconds of accumulation on any machine: long enough to be cancelled half way


def start_job(state):
    plane_alone(1.0).select_set(True)
    state["bounces"] = bpy.context.scene.cycles.max_bounces
    start_modal(state, lambda: bpy.ops.firn.add_grain_snow("INVOKE_DEFAULT", grain_radius=0.001, grain_count=GRAINS))


def check_cancelled(state):
    if any(obj.firn.is_grains for obj in bpy.data.objects):
        fail("Esc left a grain object")
    if bpy.context.scene.cycles.max_bounces != state["bounces"]:
        fail("a cancelled Add Grain Snow changed Cycles' light paths")


run_cancel_test("Add Grain Snow", start_job, "raise GRAINS", check_cancelled)
