"""Shared by the UI tests (Blender with a window under Xvfb, driven from a timer)."""

import os
import sys
import threading

import bpy

HUNG = 240.0  # s: a guard against a hang only, far beyond any run on a busy machine (CTest's TIMEOUT is 600)


def fail(message):
    print("FAIL:", message, file=sys.stderr, flush=True)
    os._exit(1)  # from a timer, sys.exit would only end the callback


def worker_alive():
    """A Firn worker thread (addon/firn/common/jobs.py names them) is computing."""
    return any(thread.name == "firn-job" and thread.is_alive() for thread in threading.enumerate())


_ui_ran = threading.Event()  # set by ui_tick while a worker is alive


def gate_worker(operator):
    """Holds the worker of `operator` (a FirnJobMixin class) before it computes until the UI's timer has run while
    that worker is alive (the test's timer calls `ui_tick`). An operator that blocks the UI while its job computes
    (the job on the main thread, or invoke waiting for its worker) never lets it pass; a busy machine only delays
    it. So the test asserts that the UI runs during a job without depending on how fast the job is."""
    def gate():
        if threading.current_thread() is threading.main_thread():
            fail(f"{operator.bl_idname}: the job computed on the main thread")
        _ui_ran.clear()  # only a tick from now on, while this worker waits, lets it go on
        if not _ui_ran.wait(HUNG):
            fail(f"{operator.bl_idname}: UI froze: the timer never ran while the worker waited")

    _wait_before_computing(operator, gate)


def _wait_before_computing(operator, wait):
    """The worker of `operator` (a FirnJobMixin class) calls wait() before it computes."""
    compute = operator.compute

    def waited(inputs, progress):
        wait()
        return compute(inputs, progress)

    operator.compute = staticmethod(waited)


_released = threading.Event()  # set by release_worker


def hold_worker(operator):
    """Holds the worker of `operator` (a FirnJobMixin class) before it computes until the test calls
    `release_worker()`: the test acts while the job surely runs, however fast or busy the machine."""
    def hold():
        if not _released.wait(HUNG):
            fail(f"{operator.bl_idname}: the test never released its worker")
        _released.clear()

    _wait_before_computing(operator, hold)


def release_worker():
    _released.set()


def strict_apply(operator):
    """An exception while `operator` (a FirnJobMixin class) applies its result fails the test (Blender would print
    it and drop the operator)."""
    import traceback

    apply = operator.apply

    def checked(self, context, inputs, result):
        try:
            apply(self, context, inputs, result)
        except Exception:
            traceback.print_exc()
            fail(f"{operator.bl_idname}: its result could not be applied")

    operator.apply = checked


def listen_keys(heard):
    """Counts in heard[key] the presses of each key of `heard` that reach a modal handler added now: one added
    later (a job's) must pass them on for it to hear them."""

    class FIRN_OT_test_listen(bpy.types.Operator):
        bl_idname = "firn.test_listen"
        bl_label = "Listen"

        def invoke(self, context, _event):
            context.window_manager.modal_handler_add(self)
            return {"RUNNING_MODAL"}

        def modal(self, _context, event):
            if event.type in heard and event.value == "PRESS":
                heard[event.type] += 1
            return {"PASS_THROUGH"}

    bpy.utils.register_class(FIRN_OT_test_listen)
    with bpy.context.temp_override(**window_context()):
        bpy.ops.firn.test_listen("INVOKE_DEFAULT")


def press(key):
    """`key`, pressed and released as a user does, in the first window."""
    window = bpy.context.window_manager.windows[0]
    window.event_simulate(type=key, value="PRESS")
    window.event_simulate(type=key, value="RELEASE")


def ui_tick():
    """The test's timer ran: a worker waiting at the gate (gate_worker) goes on."""
    if worker_alive():
        _ui_ran.set()


def job_running():
    """A Firn job's operator has not ended: its worker computes, or its result waits for the operator's next timer
    event to be applied (checking the result before that would race with the operator)."""
    from firn.common import jobs

    return bool(jobs.running_jobs())


def window_context():
    """Context override for the first window's 3D viewport, as a user's click would have."""
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return {"window": window, "screen": window.screen, "area": area,
            "region": next(r for r in area.regions if r.type == "WINDOW")}


def aim_view(space, location, pitch_deg, yaw_deg, distance):
    """Points a 3D viewport (`space`, a SpaceView3D) at `location` in perspective: tilted `pitch_deg` from looking
    straight down, turned `yaw_deg` about Z, from `distance` Blender units."""
    import math

    from mathutils import Euler, Vector

    region = space.region_3d
    region.view_perspective = "PERSP"
    region.view_location = Vector(location)
    region.view_rotation = Euler((math.radians(pitch_deg), 0.0, math.radians(yaw_deg))).to_quaternion()
    region.view_distance = distance


def passed(message="PASS"):
    """Ends the test successfully (CTest looks for PASS on stdout)."""
    print(message, flush=True)
    bpy.ops.wm.quit_blender()


def run_timer(step, interval=0.05, first_interval=0.5, persistent=False):
    """Runs `step()` on a timer until it returns False; an exception in it fails the test. `persistent`: the timer
    outlives a file load."""
    import traceback

    def tick():
        try:
            return interval if step() is not False else None
        except Exception:
            traceback.print_exc()
            fail("exception")

    bpy.app.timers.register(tick, first_interval=first_interval, persistent=persistent)


def plane_alone(size):
    """Firn enabled and a scene holding only a `size` m plane, selected and active (what each test starts from)."""
    import addon_utils

    addon_utils.enable("firn", default_set=True)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.mesh.primitive_plane_add(size=size)
    return bpy.context.object


def press_esc():
    """Esc, pressed and released as a user does, in the first window."""
    press("ESC")


def esc_once_progressing(state, hint):
    """A cancel test's 'running' phase: once the job reports progress, press Esc and go on to 'cancelled'
    (state["started"] restarts then). `hint` says what to raise if the job ends before showing progress."""
    import time

    from firn.common.jobs import running_jobs

    jobs = running_jobs()
    if not jobs:
        fail(f"the job ended before it showed progress ({hint})")
    if jobs[0].progress.fraction > 0.0:
        press_esc()
        state["phase"], state["started"] = "cancelled", time.perf_counter()
    elif time.perf_counter() - state["started"] > HUNG:
        fail("no progress: hung")


def start_modal(state, invoke):
    """Starts a job as the UI does: `invoke()` calls the operator with "INVOKE_DEFAULT" (inside the window's
    context), which must return RUNNING_MODAL with its worker thread running; state["started"] is set."""
    import time

    with bpy.context.temp_override(**window_context()):
        result = invoke()
    if result != {"RUNNING_MODAL"}:
        fail(f"expected RUNNING_MODAL, got {result}")
    if not worker_alive():
        fail("the job did not run in a worker thread")
    state["started"] = time.perf_counter()


def snow_and_mover(state, plane_size, add_mover, **snow_settings):
    """A snow layer (Add Snow Layer with `snow_settings`) on a `plane_size` m plane, then add_mover() (an animated
    object); the snow selected and active; state["objects"]: the scene's objects, before the job starts."""
    plane_alone(plane_size)
    if bpy.ops.firn.add_snow_layer(**snow_settings) != {"FINISHED"}:
        fail("Add Snow Layer failed")
    snow = bpy.context.object
    add_mover()
    snow.select_set(True)
    bpy.context.view_layer.objects.active = snow
    state["objects"] = {obj.name for obj in bpy.data.objects}


def sliding_ski(frames, reach):
    """A ski's sole (30 × 6 cm) sliding 5 cm deep from x = -reach to +reach m over frames 1…`frames`."""
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    sole = bpy.context.object
    sole.scale = (0.3, 0.06, 1.0)
    for frame, x in ((1, -reach), (frames, reach)):
        sole.location = (x, 0.0, 0.05)
        sole.keyframe_insert("location", frame=frame)


def check_scene_kept(state, name):
    """A cancelled job that adds a Volume in the snow layer's place left the scene as it was: the objects of
    state["objects"] (taken before it started) and the snow layer "Snow" shown."""
    objects = {obj.name for obj in bpy.data.objects}
    if objects != state["objects"]:
        fail(f"Esc changed the scene's objects: {sorted(objects ^ state['objects'])}")
    snow = bpy.data.objects["Snow"]
    if snow.hide_render or snow.hide_viewport:
        fail(f"a cancelled {name} hid the snow layer")


def run_cancel_test(name, start_job, hint, check_cancelled):
    """A job cancelled with Esc as a user does: `start_job(state)` starts it (start_modal); once it shows progress
    Esc is pressed; once it has ended `check_cancelled(state)` checks what it left (fail() on a fault) and the
    test passes. `hint` says what to raise if the job ends before showing progress."""
    import time

    state = {"phase": "start", "started": 0.0}

    def step():
        if state["phase"] == "start":
            start_job(state)
            state["phase"] = "running"
        elif state["phase"] == "running":
            esc_once_progressing(state, hint)
        elif state["phase"] == "cancelled":
            if not job_running():
                print(f"Esc stopped {name} in {time.perf_counter() - state['started']:.2f} s")
                check_cancelled(state)
                passed()
                return False
            if time.perf_counter() - state["started"] > HUNG:
                fail("Esc did not stop the job: hung")
        return True

    run_timer(step)
