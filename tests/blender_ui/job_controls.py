"""Blender with a window (under xvfb-run): the controls every long Firn job has, on a job that runs until it is
cancelled. While it runs, input passes on to the rest of Blender (a listener started before the job still sees
key presses), the status bar carries a Cancel button, and the Cancel button's operator or Esc stop it; opening
another file stops it too.

xvfb-run blender --factory-startup --enable-event-simulate --python job_controls.py   (exit code 0 = pass)
"""

import os
import sys
import time

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import HUNG, fail, job_running, listen_keys, passed, press, run_timer, worker_alive  # noqa: E402

state = {"phase": "start", "ticks": 0, "since": 0.0}
heard = {"K": 0}


def window():
    return bpy.context.window_manager.windows[0]


def view3d():
    area = next(a for a in window().screen.areas if a.type == "VIEW_3D")
    return area, next(r for r in area.regions if r.type == "WINDOW")


def register_waiting_job():
    from firn.common.core import firncore
    from firn.common.jobs import FirnJobMixin

    class FIRN_OT_test_wait(FirnJobMixin, bpy.types.Operator):
        """A job that computes nothing and ends only when cancelled"""

        bl_idname = "firn.test_wait"
        bl_label = "Wait"
        job_label = "Waiting"
        job_passes_events = True

        def prepare(self, _context):
            return {}

        @staticmethod
        def compute(_inputs, progress):
            started = time.perf_counter()
            while not progress.cancelled:
                if time.perf_counter() - started > HUNG:
                    return "not cancelled"
                time.sleep(0.01)
            raise firncore.Cancelled("cancelled")

        def apply(self, _context, _inputs, result):
            fail(f"the job ended by itself: {result}")

    bpy.utils.register_class(FIRN_OT_test_wait)


def invoke(operator):
    area, region = view3d()
    with bpy.context.temp_override(window=window(), screen=window().screen, area=area, region=region):
        result = operator("INVOKE_DEFAULT")
    if result != {"RUNNING_MODAL"}:
        fail(f"expected RUNNING_MODAL, got {result}")


def start_job():
    invoke(bpy.ops.firn.test_wait)
    state["since"] = time.perf_counter()


def status_bar_entries():
    """What Firn adds to the status bar now (drawn into a recording stand-in for the layout)."""
    from firn.common import jobs

    entries = []

    class Layout:
        def operator(self, idname, text="", **_kwargs):
            entries.append((idname, text))

    jobs._draw_status(type("Header", (), {"layout": Layout()})(), bpy.context)
    return entries


def step():
    state["ticks"] += 1
    phase = state["phase"]
    if phase == "start":
        addon_utils.enable("firn", default_set=True)
        register_waiting_job()
        listen_keys(heard)
        start_job()
        state["phase"], state["ticks"] = "typing", 0
    elif phase == "typing" and state["ticks"] == 3:
        if not job_running():
            fail("the job is not running")
        if status_bar_entries() != [("firn.cancel_jobs", "Cancel Waiting")]:
            fail(f"status bar shows {status_bar_entries()}")
        press("K")
        state["phase"], state["ticks"] = "typed", 0
    elif phase == "typed" and state["ticks"] == 3:
        if heard["K"] != 1:
            fail(f"the listener heard {heard['K']} key presses while the job ran, expected 1")
        bpy.ops.firn.cancel_jobs()  # what the status bar's and the panel's Cancel buttons run
        state["phase"], state["since"] = "cancel button", time.perf_counter()
    elif phase == "cancel button" and not job_running():
        print(f"Cancel stopped the job in {time.perf_counter() - state['since']:.2f} s")
        if status_bar_entries() != []:
            fail("the status bar still shows a Cancel button")
        start_job()
        state["phase"], state["ticks"] = "esc", 0
    elif phase == "esc" and state["ticks"] == 3:
        press("ESC")
        state["phase"], state["since"] = "escaped", time.perf_counter()
    elif phase == "escaped" and not job_running():
        print(f"Esc stopped the job in {time.perf_counter() - state['since']:.2f} s")
        start_job()
        state["phase"], state["ticks"] = "open", 0
    elif phase == "open" and state["ticks"] == 3:
        bpy.ops.wm.read_homefile(use_empty=True)  # Blender drops the running operator
        if job_running():
            fail("the job's operator outlived the file it ran in")
        state["phase"], state["since"] = "opened", time.perf_counter()
    elif phase == "opened" and not worker_alive():
        print(f"opening a file stopped the job in {time.perf_counter() - state['since']:.2f} s")
        passed()
        return False
    if phase in {"cancel button", "escaped", "opened"} and time.perf_counter() - state["since"] > HUNG:
        fail(f"{phase}: the job did not stop: hung")


run_timer(step, persistent=True)  # persistent: it outlives the file load
