"""Blender with a window (under xvfb-run): Bake Light Sequence started as a user would (INVOKE_DEFAULT) bakes in a
worker thread with progress naming the frame, and Esc cancels it leaving the scene as it was (no Lit Volume, the
snow layer shown). (The frames already lit stay in the cache with their markers, and a bake resumes from them:
tests/blender/test_light_sequence.py.)

xvfb-run blender --factory-startup --enable-event-simulate --python light_sequence_job.py   (exit code 0 = pass)
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ui_test  # noqa: E402
from ui_test import check_scene_kept, run_cancel_test, snow_and_mover, start_modal  # noqa: E402

FRAMES = 200  # a fraction of a second each: long enough to be cancelled half way on any machine


def setting_sun():
    """A sun that sinks from 84° to 21° over the frames."""
    bpy.ops.object.light_add(type="SUN")
    sun = bpy.context.object
    for frame, tilt in ((1, 0.1), (FRAMES, 1.2)):
        sun.rotation_euler = (tilt, 0.0, 0.0)
        sun.keyframe_insert("rotation_euler", frame=frame)


def start_job(state):
    snow_and_mover(state, 1.0, setting_sun, depth=0.05, spacing=0.04, voxel_size=0.02)
    start_modal(state, lambda: bpy.ops.firn.bake_light_sequence("INVOKE_DEFAULT", frame_start=1, frame_end=FRAMES))


def check_cancelled(state):
    check_scene_kept(state, "Bake Light Sequence")


def esc_once_frame_shown(state, hint):
    """ui_test's running phase, once the status bar says which frame is baking (the status follows progress)."""
    from firn.common.jobs import running_jobs

    jobs = running_jobs()
    if jobs and jobs[0].progress.fraction > 0.0 and not jobs[0].status.startswith("frame "):
        return
    esc_once_progressing(state, hint)


esc_once_progressing = ui_test.esc_once_progressing
ui_test.esc_once_progressing = esc_once_frame_shown
run_cancel_test("Bake Light Sequence", start_job, "raise FRAMES", check_cancelled)
