"""The world as the bake's light, rendered by Cycles: a small equirectangular radiance map per snow frame and,
for each Nishita sun, close-ups of its disc with and without it (bake/inputs.py turns them into a Sky and Suns).
A world that is just a Nishita sky is not rendered: the core computes it (bake/inputs.py NishitaWorld).

Rendering needs Blender's main thread, which the UI needs too. So the main thread only writes the world into a
.blend of its own (`Request`, milliseconds); the bake's worker thread then has a child Blender render it
(`blender -b` running this file, at the worker's low priority) while the UI keeps drawing. Scripts and background
bakes, already on the main thread, render it in place. Both run `render_world`.

No Firn imports: a child Blender runs this file alone, without the add-on.
"""

import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass

import bpy
import numpy as np
from mathutils import Euler, Matrix, Vector

SKY_MAP_SIZE = (128, 64)  # equirectangular pixels (2.8 degrees each)
SKY_MAP_SAMPLES = 16  # per pixel; a camera ray straight to the world has no noise but the pixel footprint
SUN_VIEW_SIZE = 32  # pixels across the close-up that measures a sky texture's sun disc
SUN_VIEW_SAMPLES = 64
# A camera at the origin looking along +X with +Z up renders an equirect image in Blender's Environment
# Texture convention (u = 0.5 looks along +X, u = 0.25 along +Y); checked by test_bake_inputs.py.
_EQUIRECT_CAMERA = Euler((math.pi / 2, 0.0, -math.pi / 2)).to_matrix()
_POLL_INTERVAL = 0.05  # s between looks at a child Blender and at the Cancel button
_EXCEPTION_LINE = re.compile(r"^([\w.]+(?:Error|Exception)): (.*)")


class RenderError(RuntimeError):
    """The world could not be rendered; the message says why."""


@dataclass
class Request:
    """What to render: world `world`, saved alone in `blend`, at `frame`. One map per entry of `rotations`
    (object → world, 3 × 3 nested lists); per entry of `suns` — (Nishita node name, direction towards its sun in
    the world, the sun's angular diameter in rad) — two close-ups of the disc, with and without it."""

    blend: str
    world: str
    frame: int
    rotations: list
    suns: list
    blender: str  # the Blender that renders it in a child process

    @property
    def folder(self):
        return os.path.dirname(self.blend)

    def discard(self):
        shutil.rmtree(self.folder, ignore_errors=True)


@dataclass
class Rendering:
    maps: list  # per rotation: (height, width, 3) float32 W/m²/sr, rows bottom (nadir) to top (zenith)
    discs: list  # per sun: (with disc, without disc), each (n, n, 3) float32 W/m²/sr


def request(world, frame, rotations, suns):
    """Main thread: a Request, its world written to a temporary .blend (image paths made absolute)."""
    folder = tempfile.mkdtemp(prefix="firn_world_")
    blend = os.path.join(folder, "world.blend")
    try:
        bpy.data.libraries.write(blend, {world}, path_remap="ABSOLUTE")
    except (OSError, RuntimeError) as error:
        shutil.rmtree(folder, ignore_errors=True)
        raise RenderError(f"cannot save world '{world.name}' for rendering: {error}") from error
    return Request(blend, world.name, frame, [np.asarray(r, float).tolist() for r in rotations],
                   [(name, list(direction), diameter) for name, direction, diameter in suns], bpy.app.binary_path)


def disc_field_of_view(diameter):
    """Field of view (rad) of the close-ups of a sun disc `diameter` (rad) across: twice the disc, at least half
    a degree, so a sun of any size fills a few pixels and the close-up holds all of it."""
    return max(2.0 * diameter, math.radians(0.5))


def render(request, cancelled):
    """The request rendered, its files removed. In place on the main thread, else by a child Blender; None once
    `cancelled()` turns true (the child is stopped)."""
    try:
        if threading.current_thread() is threading.main_thread():
            return render_world(bpy.data.worlds[request.world], request)
        return _render_in_child(request, cancelled)
    finally:
        request.discard()


def render_world(world, request):
    """Main thread of any Blender: renders `request` from `world` (left as it was)."""
    with WorldProbe(world, request.frame) as probe:
        discs = []
        for name, direction, diameter in request.suns:
            field_of_view = disc_field_of_view(diameter)
            with_disc = probe.close_up(direction, field_of_view)
            probe.world.node_tree.nodes[name].sun_disc = False  # the maps hold the sky without its suns
            discs.append((with_disc, probe.close_up(direction, field_of_view)))
        return Rendering([probe.equirect(rotation) for rotation in request.rotations], discs)


# --- in a child Blender -------------------------------------------------------------------------------------

def _render_in_child(request, cancelled):
    request_path = os.path.join(request.folder, "request.json")
    with open(request_path, "w", encoding="utf-8") as file:
        json.dump(asdict(request), file)
    log_path = os.path.join(request.folder, "log.txt")
    command = [request.blender, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1",
               "--python", os.path.abspath(__file__), "--", request_path]
    with open(log_path, "wb") as log:
        # Started from the worker thread, the child inherits its low priority (Linux: per-thread niceness).
        child = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT)
        try:
            while child.poll() is None:
                if cancelled():
                    return None
                time.sleep(_POLL_INTERVAL)
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
    if child.returncode != 0:
        raise RenderError(_last_error(log_path) or f"Blender exited with status {child.returncode}")
    return _load(os.path.join(request.folder, "rendering.npz"), request)


def _last_error(log_path):
    """The last Python exception in a child's log, without its type ("__main__.RenderError: why" -> "why")."""
    with open(log_path, encoding="utf-8", errors="replace") as log:
        found = [match.group(2) for match in map(_EXCEPTION_LINE.match, log) if match]
    return found[-1].strip() if found else None


def _save(rendering, path):
    arrays = {f"map{i}": image for i, image in enumerate(rendering.maps)}
    for i, (with_disc, without_disc) in enumerate(rendering.discs):
        arrays[f"with{i}"], arrays[f"without{i}"] = with_disc, without_disc
    partial = path + ".part.npz"
    np.savez(partial, **arrays)
    os.replace(partial, path)


def _load(path, request):
    with np.load(path) as arrays:
        return Rendering([arrays[f"map{i}"] for i in range(len(request.rotations))],
                         [(arrays[f"with{i}"], arrays[f"without{i}"]) for i in range(len(request.suns))])


def _child_main(request_path):
    with open(request_path, encoding="utf-8") as file:
        request = Request(**json.load(file))
    with bpy.data.libraries.load(request.blend) as (_source, loaded):
        loaded.worlds = [request.world]
    world = loaded.worlds[0]
    if world is None:
        raise RenderError(f"world '{request.world}' is missing from {request.blend}")
    _save(render_world(world, request), os.path.join(request.folder, "rendering.npz"))


# --- the probe scene ------------------------------------------------------------------------------------------

# What a Light Path node in the world reads for light that reaches snow: a volume-scattered or light-sampled ray
# (every "Is ... Ray" false; Cycles 3.4 has no "Is Volume Scatter Ray" output), one bounce in, infinitely long.
_SCATTERED_RAY = {"Ray Length": 1e30, "Ray Depth": 1.0}


def _as_seen_by_scattered_light(tree):
    """Replaces the Light Path nodes of a world tree with the values a scattered ray reads, so a world that
    shows one thing to the camera and lights with another (Is Camera Ray) is probed for its lighting."""
    for node in [node for node in tree.nodes if node.type == "LIGHT_PATH"]:
        for output in node.outputs:
            if not output.is_linked:
                continue
            value = tree.nodes.new("ShaderNodeValue")
            value.outputs[0].default_value = _SCATTERED_RAY.get(output.name, 0.0)
            for link in list(output.links):
                tree.links.new(value.outputs[0], link.to_socket)
        tree.nodes.remove(node)


class WorldProbe:
    """Renders a copy of a world with Cycles in a scene of its own: equirect maps and close-ups of the sun.

    The user's scenes, world and last render are left alone; everything made here is removed on close() but a
    render slot "Firn World Probe", reused by every bake.
    """

    def __init__(self, world, frame_current):
        self._folder = tempfile.mkdtemp(prefix="firn_world_")
        self.world = world.copy()
        self.world.cycles_visibility.camera = True  # the probe's camera rays stand for the light reaching snow
        if self.world.use_nodes and self.world.node_tree is not None:
            _as_seen_by_scattered_light(self.world.node_tree)
        self.scene = bpy.data.scenes.new("Firn World Probe")
        self.scene.world = self.world
        self.scene.frame_current = frame_current
        self.scene.render.engine = "CYCLES"
        cycles = self.scene.cycles
        cycles.device = "CPU"
        cycles.use_denoising = False
        cycles.use_adaptive_sampling = False
        cycles.pixel_filter_type = "BOX"  # a pixel is the mean radiance over its footprint
        self.scene.render.filter_size = 1.0
        self.scene.render.resolution_percentage = 100
        self.scene.render.film_transparent = False
        settings = self.scene.render.image_settings
        settings.file_format, settings.color_depth, settings.exr_codec = "OPEN_EXR", "32", "ZIP"
        self._camera_data = bpy.data.cameras.new("Firn World Probe")
        self.camera = bpy.data.objects.new("Firn World Probe", self._camera_data)
        self.scene.collection.objects.link(self.camera)
        self.scene.camera = self.camera

    def close(self):
        bpy.data.objects.remove(self.camera)
        bpy.data.cameras.remove(self._camera_data)
        bpy.data.scenes.remove(self.scene)
        bpy.data.worlds.remove(self.world)
        shutil.rmtree(self._folder, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *_exc):
        self.close()

    def equirect(self, rotation, size=SKY_MAP_SIZE, samples=SKY_MAP_SAMPLES):
        """(height, width, 3) radiance map; `rotation` (3 × 3, object → world) turns it into an object's frame."""
        camera = self._camera_data
        camera.type = "PANO"
        camera.cycles.panorama_type = "EQUIRECTANGULAR"
        camera.cycles.latitude_min, camera.cycles.latitude_max = -math.pi / 2, math.pi / 2
        camera.cycles.longitude_min, camera.cycles.longitude_max = -math.pi, math.pi
        self.camera.matrix_world = (Matrix(np.asarray(rotation).tolist()) @ _EQUIRECT_CAMERA).to_4x4()
        return self._render(size, samples)

    def close_up(self, direction, field_of_view, size=SUN_VIEW_SIZE, samples=SUN_VIEW_SAMPLES):
        """(size, size, 3) radiance seen by a square pinhole camera looking along `direction` (world)."""
        camera = self._camera_data
        camera.type = "PERSP"
        camera.sensor_fit = "HORIZONTAL"
        camera.angle = field_of_view
        self.camera.matrix_world = Vector(direction).to_track_quat("-Z", "Y").to_matrix().to_4x4()
        return self._render((size, size), samples)

    def _render(self, size, samples):
        render = self.scene.render
        render.resolution_x, render.resolution_y = size
        self.scene.cycles.samples = samples
        path = os.path.join(self._folder, "probe.exr")
        render.filepath = path
        with _spare_render_slot():
            try:
                bpy.ops.render.render(write_still=True, scene=self.scene.name)
            except RuntimeError as error:
                raise RenderError(str(error)) from error
        image = bpy.data.images.load(path, check_existing=False)
        try:
            width, height = image.size
            pixels = np.empty(width * height * 4, np.float32)
            image.pixels.foreach_get(pixels)  # scene-linear floats, rows bottom to top
        finally:
            bpy.data.images.remove(image)
        return pixels.reshape(height, width, 4)[:, :, :3].copy()


class _spare_render_slot:
    """Renders into a render slot of Firn's own, so the user's last render stays on view in its slot (Blender's
    Python cannot remove slots: the one slot is made once and reused)."""

    name = "Firn World Probe"

    def __enter__(self):
        self.image = bpy.data.images.get("Render Result")
        if self.image is not None:
            slots = self.image.render_slots
            self.previous = slots.active_index
            slot = next((slot for slot in slots if slot.name == self.name), None) or slots.new(name=self.name)
            slots.active = slot

    def __exit__(self, *_exc):
        if self.image is not None:
            self.image.render_slots.active_index = self.previous


if __name__ == "__main__":
    _child_main(sys.argv[sys.argv.index("--") + 1])
