"""The light of the tracked snow, baked frame by frame (docs/spray.md "Light"): each frame of "<snow> Tracks" is
baked with the lamps, world and objects as they stand at that frame (the skier's shadow moves with the skier)
into its own lit_####.vdb beside the sequence's files, and the Tracks object plays those once they are there.

A lit frame's marker (lit_####.json) records what it was baked from: the scene at that frame (bake/inputs.py
signature), the optics, quality and seed, and the tracked snow file it read (size and time). A frame whose marker
matches is not baked again, so an interrupted bake resumes at the first frame left, and render-farm nodes that
each bake their own frames share one folder. The core and this module write every file atomically (temporary
file, then rename), the marker after its VDB.

gather() runs on the main thread (it steps the scene through the frames); bake_frames() in the worker (no bpy).
"""

import json
import os

from ..bake import inputs as bake_inputs, state as bake_state
from ..bake.operators import core_bake, volume_optics_of
from ..common import cache
from ..common.core import firncore
from . import files


def frame_parts(signature, optics_digest, quality, seed, snow_file):
    """{component: digest} of one frame's bake: the scene's (bake_inputs.signature), the optics, the settings and
    the tracked snow file it reads."""
    return dict(signature, optics=optics_digest, settings=bake_inputs.digest(quality, seed),
                snow=bake_state.file_digest(snow_file))


def sequence_digest(directory, first, last):
    """Digest of the markers of frames first…last: what the Tracks object's bake fingerprint records."""
    return bake_inputs.digest([files.read_marker(directory, frame) for frame in range(first, last + 1)])


def is_lit(directory, frame, parts):
    """Whether frame's lit file is there and was baked from exactly `parts`."""
    return os.path.exists(files.frame_path(directory, frame, "lit")) and files.read_marker(directory, frame) == parts


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


def gather(context, tracks, frames, quality, seed):
    """Main thread: one job per frame of `frames` (scene frame numbers) with the BakeInputs of that frame and the
    parts its marker will record; the worker skips the frames already lit (is_lit, once the simulation has run).
    The scene is returned to its frame. Raises UserError (bad lamp, scale)."""
    scene = context.scene
    directory = os.path.dirname(cache.volume_path(tracks.data))
    optics = volume_optics_of(tracks)
    optics_digest = bake_state.optics_digest(tracks)
    shared = _SharedOccluders()
    jobs = []
    current = scene.frame_current
    try:
        for frame in frames:
            scene.frame_set(frame)
            snow_file = files.frame_path(directory, frame, "snow")
            signature = bake_inputs.signature(context, tracks)
            parts = frame_parts(signature, optics_digest, quality, seed, snow_file)
            inputs = bake_inputs.gather(context, tracks, occluders=lambda objects, depsgraph, space:
                                        shared.gather(objects, signature["occluders"], depsgraph, space))
            jobs.append({"frame": frame, "path": snow_file, "lit": files.frame_path(directory, frame, "lit"), "parts": parts,
                         "optics": optics, "inputs": inputs, "name": f"{tracks.name} frame {frame}"})
    finally:
        scene.frame_set(current)
    return jobs


def bake_frames(jobs, quality, seed, progress, on_frame=None):
    """Worker thread: bakes each job's tracked snow into its lit file, then writes its marker. A cancel or an
    error stops between frames: the frames done stay done (their markers say so)."""
    for index, job in enumerate(jobs):
        if on_frame:
            on_frame(index)
        if progress.cancelled:
            raise firncore.Cancelled("cancelled")
        cache.core_write(core_bake, job["path"], job["lit"], job["optics"], job["inputs"], quality, seed, progress)
        _write_marker(os.path.dirname(job["lit"]), job["frame"], job["parts"])


def all_lit(directory, first, last):
    """Whether every frame first…last has a lit file (Blender plays a sequence only whole)."""
    return all(os.path.exists(files.frame_path(directory, frame, "lit")) for frame in range(first, last + 1))


def remove_lit(directory):
    """Deletes every lit file and marker of a spray folder (Clear Bake); the tracked snow files stay."""
    if not os.path.isdir(directory):
        return
    for name in os.listdir(directory):
        if name.startswith("lit_") and (name.endswith(".vdb") or name.endswith(".json")):
            os.remove(os.path.join(directory, name))

