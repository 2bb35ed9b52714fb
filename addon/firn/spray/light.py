"""The light of a spray baked frame by frame (docs/spray.md "Light"), with the lamps, world and objects as they
stand at each frame (the skier's shadow moves with the skier): the tracked snow with the frame's lumps in it as
one medium (firncore.bake_joint: the spray's shadow on the snow, lumps resting in the groove) into lit_####.vdb,
and the lumps over the snow's surface (an occluder of the snow's albedo: its light under them) into
lit_spray_####.vdb, beside the sequence's files; the Tracks and Snow Spray objects play those once they are
there. A spray without tracks (Cut Tracks off) has its lumps baked over the snow layer's own file; the snow layer
keeps its own bake. Bake Light Sequence (bake/sequence.py) lights a snow layer's own file frame by frame the same
way (gather_layer), into lit_####.vdb of its own folder.

A lit frame's marker (lit_####.json) records what it was baked from: the scene at that frame (bake/inputs.py
signature), the optics, quality and seed, and the snow and lumps files it read (size and time). A frame whose
marker matches is not baked again, so an interrupted bake resumes at the first frame left, and render-farm nodes
that each bake their own frames share one folder. The core and this module write every file atomically
(temporary file, then rename), the marker after its VDBs.

gather(), gather_layer() and world_requests() run on the main thread (they step the scene through the frames);
light_worlds() and bake_frames() in the worker (no bpy).
"""

import contextlib
import json
import os

from ..bake import inputs as bake_inputs, state as bake_state
from ..bake.operators import core_bake, core_light, render_world, volume_optics_of
from ..common import cache
from ..common.core import firncore
from ..common.errors import UserError
from ..properties import is_spray
from . import files

# The snow's surface as the lumps' occluder: flat parts merged (the lumps see it from a few centimetres). It is
# meshed one voxel under the surface, where the snow's density ramp has become opaque: lumps resting in the
# groove then lie outside it (inside a closed mesh of albedo 0.97 a lump's paths bounce some 30 times, and the
# bake's tracing budget leaves all the lumps to its diffusion: measured, 0 traced voxels of 774).
SURFACE_ADAPTIVITY = 0.5


def frame_parts(signature, optics_digest, quality, seed, snow_file, spray_file):
    """{component: digest} of one frame's bake: the scene's (bake_inputs.signature), the optics, the settings and
    the snow and lumps files it reads."""
    return dict(signature, optics=optics_digest, settings=bake_inputs.digest(quality, seed),
                snow=bake_state.file_digest(snow_file), spray=bake_state.file_digest(spray_file))


def read_files(job):
    """The job's parts with its files' digests as they are now (the simulation may have rewritten them)."""
    snow_file, spray_file = job["paths"]
    job["parts"].update(snow=bake_state.file_digest(snow_file), spray=bake_state.file_digest(spray_file))


def sequence_digest(directory, first, last):
    """Digest of the markers of frames first…last: what a lit sequence's bake fingerprint records."""
    return bake_inputs.digest([files.read_marker(directory, frame) for frame in range(first, last + 1)])


def is_lit(job):
    """Whether the job's lit files are there and were baked from exactly its parts."""
    return (all(os.path.exists(path) for path in job["outputs"] if path)
            and files.read_marker(job["directory"], job["frame"]) == job["parts"])


def _write_marker(directory, frame, parts):
    path = files.marker_path(directory, frame)
    staged = path + ".tmp"
    with open(staged, "w", encoding="utf-8") as stream:
        json.dump(parts, stream, sort_keys=True)
    os.replace(staged, path)


class _SharedOccluders:
    """Occluders gathered once for objects that stand still over the frames and again per frame for the ones
    that move (a skier's body): the static ones' triangles are shared, not copied per frame."""

    def __init__(self):
        self._static = {}  # object name: (digest, [Occluder])

    def gather(self, objects, digests, depsgraph, frame):
        occluders = []
        for obj in objects:
            kept = self._static.get(obj.name)
            if kept is not None and kept[0] == digests.get(obj.name):
                occluders += kept[1]
                continue
            parts = bake_inputs.gather_occluders([obj], depsgraph, frame)
            self._static[obj.name] = (digests.get(obj.name), parts)
            occluders += parts
        return occluders


def medium_object(spray, tracks):
    """The snow the lumps are baked with: the tracked snow, or the snow layer where the spray has none."""
    return tracks if tracks is not None else spray.firn.spray.source


def _joint_optics(spray, snow):
    """The optics the lumps and the snow are baked with, as one medium: UserError when they differ."""
    if bake_state.optics_digest(spray) != bake_state.optics_digest(snow):
        raise UserError(f"'{spray.name}' and '{snow.name}' have different Snow Material optics: their light is "
                        "baked together, as one snow. Give them the same settings, or turn Bake Light off")
    return volume_optics_of(snow)


@contextlib.contextmanager
def _sequences_unloaded(scene):
    """Firn's Volume sequences (sprays, tracks, lit layers) left out of the depsgraph while the scene steps through
    frames: each would load its frame's file at every step (44 ms a frame for a Lit Volume of 40,000 voxels, 0.65
    without; bench/light_sequence_bench.py), and no Volume lights or shades a bake."""
    hidden = [obj for obj in scene.objects if is_spray(obj) and not obj.hide_viewport]
    for obj in hidden:
        obj.hide_viewport = True
    try:
        yield
    finally:
        for obj in hidden:
            obj.hide_viewport = False


def gather_frames(context, medium, frames, job_of):
    """Main thread: one job per frame of `frames` (scene frame numbers): job_of(frame, signature) (its files, the
    parts its marker will record) with the BakeInputs of `medium` at that frame; the worker skips the frames already
    lit (is_lit). The scene is returned to its frame. Raises UserError (bad lamp, scale)."""
    scene = context.scene
    shared = _SharedOccluders()
    current = scene.frame_current
    try:
        with _sequences_unloaded(scene):
            return [_frame_job(context, medium, frame, job_of, shared) for frame in frames]
    finally:
        scene.frame_set(current)


def _frame_job(context, medium, frame, job_of, shared):
    """One frame's job (gather_frames), the scene stepped to that frame."""
    context.scene.frame_set(frame)
    signature = bake_inputs.signature(context, medium)
    inputs = bake_inputs.gather(context, medium, occluders=lambda objects, depsgraph, space:
                                shared.gather(objects, signature["occluders"], depsgraph, space))
    return dict(job_of(frame, signature), frame=frame, inputs=inputs)


def gather(context, spray, tracks, frames, quality, seed):
    """Main thread: a spray's frame jobs (gather_frames): its tracked snow and lumps, baked together (_bake_frame).
    Raises UserError (bad lamp, scale, optics that differ)."""
    snow = medium_object(spray, tracks)
    directory = cache.sequence_folder(spray.data)
    layer = spray.firn.spray.source
    snow_layer_file = cache.volume_path(layer.data)
    optics = _joint_optics(spray, snow)
    optics_digest = bake_state.optics_digest(snow)

    def job_of(frame, signature):
        paths = files.medium_paths(directory, frame, snow_layer_file, tracked=tracks is not None)
        outputs = (files.frame_path(directory, frame, "lit") if tracks is not None else None,
                   files.frame_path(directory, frame, "lit_spray"))
        parts = dict(frame_parts(signature, optics_digest, quality, seed, *paths),
                     place=bake_state.place_digest(layer))
        return {"paths": paths, "outputs": outputs, "directory": directory, "optics": optics, "parts": parts,
                "name": f"{spray.name} frame {frame}", "bake": _bake_frame}

    return gather_frames(context, snow, frames, job_of)


def gather_layer(context, snow, optics_of, frames, directory, quality, seed):
    """Main thread: a snow layer's frame jobs (gather_frames, bake/sequence.py): its own file baked with the optics
    of `optics_of` at each frame into lit_####.vdb of `directory` (_bake_layer_frame). Its marker names no lumps
    file (that path holds none); its snow is the layer's file and transform (bake/state.py snow_digest). Raises
    UserError (bad lamp, scale, optics)."""
    snow_file = cache.volume_path(snow.data)
    optics = volume_optics_of(optics_of)
    optics_digest = bake_state.optics_digest(optics_of)

    def job_of(frame, signature):
        paths = files.medium_paths(directory, frame, snow_file, tracked=False)
        # The snow's part as Bake Scattering's: its file and its transform (moved, the objects and the sky around
        # it are elsewhere).
        parts = dict(frame_parts(signature, optics_digest, quality, seed, *paths), snow=bake_state.snow_digest(snow))
        return {"paths": paths, "outputs": (files.frame_path(directory, frame, "lit"), None),
                "directory": directory, "optics": optics, "parts": parts,
                "name": f"{snow.name} frame {frame}", "bake": _bake_layer_frame}

    return gather_frames(context, snow, frames, job_of)


def world_requests(scene, jobs):
    """Main thread: [(world, jobs)]: one world request (bake/inputs.py world_request) for each distinct world among
    the jobs whose sky is still to compute or render, made at the first of its frames (an animated world, a
    Nishita sun setting or a keyframed strength, gets one a frame). The scene is returned to its frame."""
    groups = {}
    for job in jobs:
        if job["inputs"].sky is None:
            groups.setdefault(job["parts"]["sky"], []).append(job)
    requests = []
    current = scene.frame_current
    try:
        with _sequences_unloaded(scene):
            for group in groups.values():
                scene.frame_set(group[0]["frame"])
                requests.append((bake_inputs.world_request(scene, [job["inputs"].frame for job in group]), group))
    except BaseException:
        discard_worlds(requests)
        raise
    finally:
        scene.frame_set(current)
    return requests


def light_worlds(requests, todo, progress):
    """Worker thread: renders or computes the world requests that jobs of `todo` need and completes those jobs'
    light. Every request is discarded afterwards, whatever happens (what an unrendered one saved is removed)."""
    wanted = {id(job) for job in todo}
    try:
        for world, group in requests:
            needed = [job for job in group if id(job) in wanted]
            if needed:
                render_world({"world": world, "jobs": needed}, progress)
    finally:
        discard_worlds(requests)


def discard_worlds(requests):
    for world, _group in requests:
        world.discard()


def _bake_frame(job, quality, seed, progress):
    """A frame's two bakes. The tracked snow with the lumps in it, as one medium (firncore.bake_joint): the
    lumps' shadow on the snow, lumps resting in the groove. The lumps with the snow's surface as an occluder that
    reflects the snow's white-sky albedo (its light under them, its shadow on them). Where the lumps are over the
    gathering budget both bakes light trace them (docs/spray.md "Light"; some 28 processor s a frame at Final, 7 at
    Draft). A frame without lumps gets their lit file with empty light grids, unbaked (without tracks there is
    nothing else to bake that frame). Returns the bakes' processor seconds (their stats' cpu_seconds)."""
    (snow, spray), (lit, lit_spray) = job["paths"], job["outputs"]
    settings = dict(quality=quality, seed=seed, progress=progress, **core_light(job["inputs"]))
    seconds = 0.0
    if lit is not None:
        seconds += _processor_seconds(firncore.bake_joint([snow, spray], [lit, None], job["optics"], **settings))
    if firncore.grid_statistics(spray, "density")["active_voxels"] == 0:
        firncore.write_empty_light(spray, lit_spray, job["optics"], quality, seed)
        return seconds
    voxel = firncore.grid_statistics(snow, "surface")["voxel_size"]
    vertices, triangles = firncore.snow_surface_mesh(snow, adaptivity=SURFACE_ADAPTIVITY, isovalue=-voxel)
    settings["occluders"].append((vertices, triangles, job["optics"].white_sky_albedo))
    return seconds + _processor_seconds(firncore.bake(spray, job["optics"], output_path=lit_spray, **settings))


def _processor_seconds(stats):
    return sum(stats["cpu_seconds"].values())


def _bake_layer_frame(job, quality, seed, progress):
    """A snow layer's frame (gather_layer): its file baked into the frame's lit file. Returns the processor
    seconds."""
    (snow, _lumps), (lit, _none) = job["paths"], job["outputs"]
    return _processor_seconds(core_bake(snow, lit, job["optics"], job["inputs"], quality, seed, progress))


def bake_frames(jobs, quality, seed, progress, on_frame=None):
    """Worker thread: bakes each job's lit files (its "bake": a spray's snow and lumps, or a snow layer's own file),
    then writes its marker; on_frame(index) before each. A cancel or an error stops between frames: the frames done
    stay done (their markers say so). Returns each frame's processor seconds."""
    seconds = []
    for index, job in enumerate(jobs):
        if on_frame:
            on_frame(index)
        if progress.cancelled:
            raise firncore.Cancelled("cancelled")
        seconds.append(cache.core_write(job["bake"], job, quality, seed, progress))
        _write_marker(job["directory"], job["frame"], job["parts"])
    return seconds


def all_lit(directory, first, last, kind="lit"):
    """Whether every frame first…last has a lit file of `kind` ("lit": the tracked snow's, "lit_spray": the
    lumps'): Blender plays a sequence only whole."""
    return all(os.path.exists(files.frame_path(directory, frame, kind)) for frame in range(first, last + 1))


def remove_lit(directory):
    """Deletes every lit file (the tracked snow's and the lumps') and marker of a spray folder; the simulated files
    stay."""
    if not os.path.isdir(directory):
        return
    for name in os.listdir(directory):
        if name.startswith("lit_") and (name.endswith(".vdb") or name.endswith(".json")):
            os.remove(os.path.join(directory, name))

