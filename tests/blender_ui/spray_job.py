"""Blender with a window (under xvfb-run): Add Snow Spray started as a user would (INVOKE_DEFAULT) simulates in a
worker thread with progress, and Esc cancels it leaving the scene as it was (no spray or tracks object, the snow
layer shown). The frames already written stay in the cache: the same Add Snow Spray resumes from them.

xvfb-run blender --factory-startup --enable-event-simulate --python spray_job.py   (exit code 0 = pass)
"""

import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import check_scene_kept, run_cancel_test, sliding_ski, snow_and_mover, start_modal  # noqa: E402

FRAMES = 400  # seconds of simulation on any machine: long enough to be cancelled half way


def ski():
    """A ski's sole sliding 1.6 m through the snow over the frames."""
    sliding_ski(FRAMES, 0.8)


def start_job(state):
    snow_and_mover(state, 2.0, ski, depth=0.1, spacing=0.05, voxel_size=0.01)
    start_modal(state, lambda: bpy.ops.firn.add_snow_spray("INVOKE_DEFAULT", frame_start=1, frame_end=FRAMES,
                                                           rate=200000.0))


def check_cancelled(state):
    check_scene_kept(state, "Add Snow Spray")


run_cancel_test("Add Snow Spray", start_job, "raise FRAMES", check_cancelled)
