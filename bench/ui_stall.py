"""How long Blender's UI stalls during Add Snow Layer and Bake Scattering on the car sample, as a user runs them.

bench/ui_stall.sh runs it twice: in the background it builds the car scene and saves it (blender -b ... -- SCENE),
then in a window (xvfb-run) it opens that scene and measures (blender SCENE ...).

A timer ticks every 10 ms on the main thread; a stall is the longest gap between two ticks. Each operator is
measured in three phases: its invoke (main thread: reads the scene before the worker starts), the worker
(main thread free: the timer should keep ticking), and the end (main thread: the result written into Blender,
up to the first tick after the job). Goal: <= 0.1 s while the worker runs. Timings vary with the machine's load.

Starting the bake: "sky ready" is when the bake's worker has its sky (its status leaves "Computing the sky" or
"Rendering the world"), and the longest stall until then is the UI's cost of the world. The car's world is a
Nishita sky, computed by the core; `-- --world rendered` plugs its Strength through a Value node (the same light)
so Cycles renders it instead (bake/world_probe.py), the path of every other world.

Blender's own drawing is told apart: a draw handler times each redraw of the 3D viewport (under Xvfb Blender draws
on the CPU, and Solid mode's anti-aliasing redraws the view 8 times after any change), and "outside drawing" is
the longest gap with no viewport redraw in it. Before each operator the bench waits until the viewport has not
redrawn for a second, so the redraws that the bench's own selection change causes are not counted.
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
from ui_test import window_context, worker_alive  # noqa: E402

TICK = 0.01  # s
SETTLED = 1.0  # s without a viewport redraw before an operator starts
state = {"phase": "start", "last": 0.0, "rows": [], "draws": [], "draw_began": 0.0}
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
WORLD_RENDERED = ARGS[ARGS.index("--world") + 1:][:1] == ["rendered"] if "--world" in ARGS else False
SKY_STATUSES = ("Computing the sky", "Rendering the world")  # bake/operators.py job_status
HEADER = ("| operator | invoke (s) | longest stall while the worker runs (s) | of it outside drawing (s) | end (s) "
          "| viewport redraws | longest redraw (s) | ticks | total (s) | sky ready (s) | longest stall until then (s) |"
          "\n|---|---|---|---|---|---|---|---|---|---|---|")


def _draw_began():
    state["draw_began"] = time.perf_counter()


def _draw_ended():
    state["draws"].append((state["draw_began"], time.perf_counter()))


def settled(now):
    """True once the 3D viewport has not redrawn for SETTLED seconds."""
    last = state["draws"][-1][1] if state["draws"] else 0.0
    return now - last > SETTLED


class Stalls:
    """Longest gap between timer ticks, per phase of one operator, and the viewport's redraws meanwhile."""

    def __init__(self, name):
        self.name, self.invoke, self.worker, self.end, self.ticks = name, 0.0, 0.0, 0.0, 0
        self.outside_drawing, self.seconds, self.first_draw = 0.0, 0.0, len(state["draws"])
        self.sky_ready, self.sky_stall = None, 0.0

    def gap(self, began, ended):
        """A gap between ticks in the worker phase; also kept apart when no viewport redraw falls in it, and
        while the bake's worker makes its sky."""
        self.worker = max(self.worker, ended - began)
        if self.sky_ready is None:
            self.sky_stall = max(self.sky_stall, ended - began)
            from firn.common.jobs import running_jobs  # the add-on is enabled by now

            statuses = [job.status for job in running_jobs()]  # "" until the operator's first timer event
            if statuses and all(status and not status.startswith(SKY_STATUSES) for status in statuses):
                self.sky_ready = ended - self.began
        if not any(began <= start <= ended for start, _end in state["draws"][self.first_draw:]):
            self.outside_drawing = max(self.outside_drawing, ended - began)

    def row(self):
        draws = [end - start for start, end in state["draws"][self.first_draw:]]
        return (f"| {self.name} | {self.invoke:.3f} | {self.worker:.3f} | {self.outside_drawing:.3f} "
                f"| {self.end:.3f} | {len(draws)} | {max(draws, default=0.0):.3f} | {self.ticks} "
                f"| {self.seconds:.1f} | {self._sky()} |")

    def _sky(self):
        if self.sky_ready is None or not self.name.startswith("Bake"):
            return "– | –"
        return f"{self.sky_ready:.2f} | {max(self.invoke, self.sky_stall):.3f}"


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
    if worker_alive():
        stalls.gap(state["last"], now)
        stalls.ticks += 1
    else:
        state["ended"] = True
    return False


def plug_strength_through_a_node(world):
    """The same sky, no longer the exact Nishita chain the core computes: Cycles renders it."""
    tree = world.node_tree
    value = tree.nodes.new("ShaderNodeValue")
    background = tree.nodes["Background"]
    value.outputs[0].default_value = background.inputs["Strength"].default_value
    tree.links.new(value.outputs[0], background.inputs["Strength"])


def tick():
    try:
        now = time.perf_counter()
        phase = state["phase"]
        if phase == "start":
            addon_utils.enable("firn", default_set=True)
            if WORLD_RENDERED:
                plug_strength_through_a_node(bpy.context.scene.world)
            targets = [obj for obj in bpy.data.objects if obj.type == "MESH"]
            bpy.ops.object.select_all(action="DESELECT")
            for obj in targets:
                obj.select_set(True)
            bpy.context.view_layer.objects.active = targets[0]
            state["phase"] = "selected targets"
        elif phase == "selected targets" and settled(now):
            start("Add Snow Layer", bpy.ops.firn.add_snow_layer, **car_under_snow.SNOW)
            state["phase"] = "snow"
        elif phase == "snow" and measure(now):
            snow = bpy.context.active_object
            bpy.ops.object.select_all(action="DESELECT")
            snow.select_set(True)
            state["phase"] = "selected snow"
        elif phase == "selected snow" and settled(now):
            start("Bake Scattering (Final)", bpy.ops.firn.bake_scattering, quality="FINAL")
            state["phase"] = "bake"
        elif phase == "bake" and measure(now):
            print(HEADER)
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
    bpy.types.SpaceView3D.draw_handler_add(_draw_began, (), "WINDOW", "PRE_VIEW")
    bpy.types.SpaceView3D.draw_handler_add(_draw_ended, (), "WINDOW", "POST_PIXEL")
    bpy.app.timers.register(tick, first_interval=1.0)
