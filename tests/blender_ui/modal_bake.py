"""Blender with a window (under xvfb-run): Bake Scattering as a user starts it. It runs in a worker thread while
the UI keeps running; Esc during a second bake (while a child Blender renders the new sky world) leaves the first
bake's file, material and fingerprint intact; a third bake under that sky completes.

xvfb-run blender --factory-startup --enable-event-simulate --python modal_bake.py   (exit code 0 = pass)
"""

import os
import sys
import time

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ui_test import (  # noqa: E402
    HUNG, fail, gate_worker, job_running, passed, press_esc, run_timer, ui_tick, window_context, worker_alive)

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "blender"))

state = {"phase": "start", "ticks": 0, "since": 0.0, "while_computing": 0}
FOLDER = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"firn_modal_bake_{os.getpid()}")


def setup():
    from bake_helpers import uniform_world, volume_object, write_volume

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    os.makedirs(FOLDER, exist_ok=True)
    uniform_world((1.0, 1.0, 1.0))
    path = write_volume(os.path.join(FOLDER, "slab.vdb"), 0.01, (-40, -40, -29), (39, 39, 0), 300.0)
    slab = volume_object(path, "Slab")
    slab.select_set(True)
    return slab


def sky_world():
    """A world that is not a plain colour (a Nishita sky with its sun): the bake's worker has the core compute
    it (no render on the main thread)."""
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    world.node_tree.links.new(sky.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    bpy.context.scene.world = world


def start_bake(quality):
    with bpy.context.temp_override(**window_context()):
        result = bpy.ops.firn.bake_scattering("INVOKE_DEFAULT", quality=quality)
    if result != {"RUNNING_MODAL"}:
        fail(f"expected RUNNING_MODAL, got {result}")
    if not worker_alive():  # the operator returned to the UI while its worker thread bakes
        fail("the bake did not run in a worker thread")
    state["since"] = time.perf_counter()
    state["ticks"], state["while_computing"] = 0, 0


def file_bytes(obj):
    with open(bpy.path.abspath(obj.data.filepath), "rb") as file:
        return file.read()


def step():
    from firn.material import nodes as materials

    state["ticks"] += 1
    state["while_computing"] += worker_alive()
    ui_tick()
    phase = state["phase"]
    slab = bpy.data.objects.get("Slab")
    if phase == "start":
        addon_utils.enable("firn", default_set=True)
        from firn.bake.operators import FIRN_OT_bake_scattering

        gate_worker(FIRN_OT_bake_scattering)  # its worker bakes only once the UI has run beside it
        setup()
        start_bake("DRAFT")
        state["phase"] = "baking"
    elif phase == "baking" and not job_running():
        # The UI (this timer) ran while the worker baked (gate_worker); how often depends on the load.
        if slab.firn.bake_state != "BAKED":
            fail(f"after the bake the state is {slab.firn.bake_state}")
        print(f"bake finished after {time.perf_counter() - state['since']:.2f} s with "
              f"{state['while_computing']} UI ticks while it computed")
        state["before"] = (file_bytes(slab), slab.firn.bake_fingerprint)
        sky_world()
        start_bake("REFERENCE")
        state["phase"] = "second"
    elif phase == "second" and state["ticks"] == 4:
        if not job_running():
            fail("the second bake ended before Esc could be tested")
        press_esc()
        state["phase"], state["since"] = "cancelled", time.perf_counter()
    elif phase == "cancelled" and not job_running():
        print(f"Esc stopped the bake in {time.perf_counter() - state['since']:.2f} s")
        if (file_bytes(slab), slab.firn.bake_fingerprint) != state["before"]:
            fail("Esc changed the previous bake's file or fingerprint")
        if not materials.is_baked_material(materials.snow_material(slab)):
            fail("Esc changed the material")
        if os.path.exists(bpy.path.abspath(slab.data.filepath) + ".firn-bake.vdb"):
            fail("a staged file was left behind")
        if slab.firn.bake_state != "OUTDATED":  # the world changed since the kept bake
            fail(f"state {slab.firn.bake_state} after the cancelled re-bake")
        start_bake("DRAFT")
        state["phase"] = "sky"
    elif phase == "sky" and not job_running():
        if slab.firn.bake_state != "BAKED" or "sky Nishita" not in slab.firn.bake_summary:
            fail(f"the bake under a sky texture: {slab.firn.bake_state}, '{slab.firn.bake_summary}'")
        print(f"sky bake: {slab.firn.bake_summary}")
        passed()
        return False
    elif phase in {"baking", "cancelled", "sky"} and time.perf_counter() - state["since"] > HUNG:
        fail(f"{phase}: hung")


run_timer(step)
