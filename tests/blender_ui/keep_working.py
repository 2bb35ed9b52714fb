"""Blender with a window (under xvfb-run): the user keeps working beside Firn's sequence jobs. While Add Snow Spray,
Bake Sequence and Bake Light Sequence run, key presses pass on to the rest of Blender; the operators that would
start a second job, rewrite the snow or remove the files being written refuse; Esc pressed while the animation plays
passes on to Blender and the job runs on; a new file saved meanwhile gets its snow files next to it once the job has
ended, not before; a scene switched to meanwhile gets nothing, and the job's own scene gets it when the job runs
again there (reusing what was baked); and deleting an object the job came from ends it cleanly: Bake Sequence lights
the Tracks of a spray whose Snow Spray object was deleted, Bake Light Sequence adds no Lit Volume for a deleted snow
layer and leaves the frames it baked in the cache (its warning says where).

xvfb-run blender --factory-startup --enable-event-simulate --python keep_working.py   (exit code 0 = pass)
"""

import os
import shutil
import sys
import tempfile
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import (  # noqa: E402
    HUNG, fail, hold_worker, job_running, listen_keys, passed, press, release_worker, run_timer, snow_and_mover,
    sliding_ski, start_modal, strict_apply, window_context)

FRAMES = 4
FOLDER = os.path.join(tempfile.gettempdir(), f"firn_keep_working_{os.getpid()}")  # not the session's snow cache
state = {"phase": "start", "ticks": 0, "since": 0.0}
KEY = "F13"  # bound to nothing: no menu opens to take the next presses
heard = {KEY: 0, "ESC": 0}


def ski_and_sun():
    """A ski's sole sliding 0.8 m through the snow over the frames, under a sun."""
    sliding_ski(FRAMES, 0.4)
    bpy.ops.object.light_add(type="SUN", rotation=(0.6, 0.0, 0.0))


def make_active(name):
    for obj in bpy.context.selected_objects:
        obj.select_set(False)
    obj = bpy.data.objects[name]
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj


def refuses(operator):
    """`operator`'s poll, in the window's context, is False."""
    with bpy.context.temp_override(**window_context()):
        return not operator.poll()


def hold_the_jobs():
    from firn.bake.sequence import FIRN_OT_bake_light_sequence
    from firn.spray.operators import FIRN_OT_add_snow_spray, FIRN_OT_bake_sequence

    for operator in (FIRN_OT_add_snow_spray, FIRN_OT_bake_sequence, FIRN_OT_bake_light_sequence):
        hold_worker(operator)
        strict_apply(operator)


def start(phase, invoke):
    start_modal(state, invoke)
    state["phase"], state["ticks"] = phase, 0


def check_held(refused, meanwhile=lambda: None):
    """The job's worker is still held: the key pressed meanwhile reached the listener behind the job and each
    operator of `refused` refuses; then `meanwhile()` does what the user does."""
    if heard[KEY] != state["heard"] + 1:
        fail(f"{state['phase']}: the key press did not pass the job ({heard[KEY] - state['heard']} heard)")
    for operator in refused:
        if not refuses(operator):
            fail(f"{state['phase']}: {operator.idname_py()} may start while a Firn job runs")
    meanwhile()


def release(then=lambda: None):
    """Once what the user did has been handled, `then()` checks it, and the worker goes on."""
    if not job_running():
        fail(f"{state['phase']}: the job ended while its worker was held")
    then()
    release_worker()
    state["since"] = time.perf_counter()


def save_new_file():
    """The user saves the new file while the job runs: its snow stays where the job reads and writes it."""
    os.makedirs(FOLDER, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(FOLDER, "keep_working.blend"))
    if os.path.normpath(bpy.path.abspath(bpy.data.objects["Snow"].data.filepath)).startswith(FOLDER):
        fail("the first save moved the snow files while a job used them")


def check_moved_beside_the_file():
    """Once the job has ended, the snow files of the file saved meanwhile are moved next to it, the job's too."""
    for name in ("Snow", "Snow Spray", "Snow Tracks"):
        volume = bpy.data.objects[name].data
        if not (volume.filepath.startswith("//") and os.path.exists(bpy.path.abspath(volume.filepath))):
            fail(f"'{name}' reads {volume.filepath} after the job, not a file next to the saved .blend")


def switch_scene():
    """The user shows a new scene while the job runs."""
    state["scene"] = bpy.context.window_manager.windows[0].scene
    bpy.context.window_manager.windows[0].scene = bpy.data.scenes.new("Other")


def nothing_in_either_scene():
    """The job ended while the other scene was shown: no Lit Volume anywhere; the user shows the job's scene again."""
    if any(obj.firn.spray.role == "LIGHT" for obj in bpy.data.objects):
        fail("Bake Light Sequence added a Lit Volume while another scene was shown")
    bpy.context.window_manager.windows[0].scene = state["scene"]
    bpy.data.scenes.remove(bpy.data.scenes["Other"])


def play_esc_and_delete_snow():
    """The user plays the animation, presses Esc to stop it, and deletes the snow layer."""
    with bpy.context.temp_override(**window_context()):
        bpy.ops.screen.animation_play()
    state["esc"] = heard["ESC"]
    press("ESC")
    remove("Snow")


def esc_passed_on():
    """The Esc pressed while the animation played went on to Blender (which stops the playback) and left the job
    running."""
    from firn.common.jobs import running_jobs

    if running_jobs()[0].progress.cancelled:
        fail("Esc pressed to stop the animation cancelled the job")
    if heard["ESC"] != state["esc"] + 1:
        fail("Esc pressed while the animation played did not pass the job")
    with bpy.context.temp_override(**window_context()):
        bpy.ops.screen.animation_cancel(restore_frame=True)


def step():
    state["ticks"] += 1
    phase = state["phase"]
    if phase == "start":
        snow_and_mover(state, 1.0, ski_and_sun, depth=0.1, spacing=0.05, voxel_size=0.02)
        hold_the_jobs()
        listen_keys(heard)
        make_active("Snow")
        bpy.data.objects["Plane.001"].select_set(True)  # the ski
        start("spray", lambda: bpy.ops.firn.add_snow_spray("INVOKE_DEFAULT", frame_start=1, frame_end=FRAMES))
    elif phase in PLAN and state["ticks"] == 3:
        if not job_running():
            fail(f"{phase}: the job ended while its worker was held")
        state["heard"] = heard[KEY]
        press(KEY)
    elif phase in PLAN and state["ticks"] == 6:
        check_held(*PLAN[phase][:2])
    elif phase in PLAN and state["ticks"] == 9:
        release(*PLAN[phase][2:])  # an Esc that stopped the playback left the job running
        state["phase"] = phase + " ends"
    elif phase == "spray ends" and not job_running():
        if {"Snow Spray", "Snow Tracks"} - set(bpy.data.objects.keys()):
            fail(f"Add Snow Spray made {sorted(bpy.data.objects.keys())}")
        check_moved_beside_the_file()
        make_active("Snow Spray")
        start("sequence", lambda: bpy.ops.firn.bake_sequence("INVOKE_DEFAULT", quality="DRAFT"))
    elif phase == "sequence ends" and not job_running():
        tracks = bpy.data.objects["Snow Tracks"]
        if "lit_" not in os.path.basename(tracks.data.filepath) or tracks.firn.bake_state != "BAKED":
            fail(f"the Tracks of a deleted Snow Spray play {tracks.data.filepath}, state {tracks.firn.bake_state}")
        make_active("Snow Tracks")
        with bpy.context.temp_override(**window_context()):
            if bpy.ops.firn.clear_snow_spray() != {"FINISHED"}:
                fail("Clear Snow Spray refused once the bake had ended")
        make_active("Snow")
        start("switched", light_frames)
    elif phase == "switched ends" and not job_running():
        nothing_in_either_scene()
        make_active("Snow")
        start("lit", light_frames)
    elif phase == "lit ends" and not job_running():
        lit = [obj for obj in bpy.data.objects if obj.firn.spray.role == "LIGHT"]
        if len(lit) != 1 or "(0 baked now" not in lit[0].firn.bake_summary:
            fail(f"Bake Light Sequence in its own scene again: {[obj.firn.bake_summary for obj in lit]}")
        make_active(lit[0].name)
        with bpy.context.temp_override(**window_context()):
            if bpy.ops.firn.clear_light_sequence() != {"FINISHED"}:
                fail("Clear Light Sequence refused once the bake had ended")
        make_active("Snow")
        start("light", light_frames)  # three frames baked afresh: the layer is deleted during the bake
    elif phase == "light ends" and not job_running():
        if any(obj.firn.spray.role == "LIGHT" for obj in bpy.data.objects):
            fail("Bake Light Sequence added a Lit Volume for a deleted snow layer")
        from firn.common import cache

        folder = cache.spray_folder("Snow Lit")[0]  # where the warning says the frames are
        if sorted(name for name in os.listdir(folder) if name.endswith(".vdb")) != [
                f"lit_{frame:04d}.vdb" for frame in (1, 2, 3)]:
            fail(f"the lit frames of a deleted snow layer: {os.listdir(folder)}")
        shutil.rmtree(FOLDER)  # the saved file and its snow
        passed()
        return False
    elif phase.endswith(" ends") and time.perf_counter() - state["since"] > HUNG:
        fail(f"{phase}: hung")


def light_frames():
    return bpy.ops.firn.bake_light_sequence("INVOKE_DEFAULT", frame_start=1, frame_end=3, quality="DRAFT")


def remove(name):
    bpy.data.objects.remove(bpy.data.objects[name])


PLAN = {  # per job: what refuses while it runs, what the user does meanwhile, and how that ended
    "spray": ([bpy.ops.firn.add_snow_spray, bpy.ops.firn.bake_light_sequence, bpy.ops.firn.bake_scattering,
               bpy.ops.firn.regenerate_snow], save_new_file),
    "sequence": ([bpy.ops.firn.clear_snow_spray, bpy.ops.firn.bake_sequence, bpy.ops.firn.bake_scattering],
                 lambda: remove("Snow Spray")),
    "switched": ([bpy.ops.firn.bake_light_sequence], switch_scene),
    "lit": ([], lambda: None),
    "light": ([bpy.ops.firn.bake_light_sequence, bpy.ops.firn.add_snow_spray, bpy.ops.firn.regenerate_snow],
              play_esc_and_delete_snow, esc_passed_on),
}
run_timer(step)
