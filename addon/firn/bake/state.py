"""Whether a snow object's bake still matches the scene.

At bake time a fingerprint of everything the bake depends on is stored on the object (obj.firn.bake_fingerprint,
JSON {component: digest}); the panel compares it with the live scene at every redraw. Components: the sun lamps
(and lamps ignored), the world, the occluders ({object name: digest of its transform, evaluated shape, modifiers
and albedo}, so a change names the object), the optics, and the snow itself (its file's size and modification
time, and its transform). A sequence baked frame by frame (Bake Sequence, spray/light.py: a spray's lumps and
its tracked snow, baked together; Bake Light Sequence: a layer's own snow) is compared through the marker of the
frame it shows. Nothing here renders or reads grids.
"""

import json
import os

import bpy

from ..common import cache
from ..material import optics
from ..spray import files as spray_files
from . import inputs as bake_inputs

NONE, BAKED, OUTDATED = "NONE", "BAKED", "OUTDATED"
STATES = (
    (NONE, "Not Baked", "Rendered from its optics by brute-force path tracing", "RADIOBUT_OFF", 0),
    (BAKED, "Baked", "Rendered from its bake, which matches the scene", "CHECKMARK", 1),
    (OUTDATED, "Needs Re-bake", "The lights, the world, the objects around, the optics or the snow changed since "
     "the bake", "ERROR", 2),
)
# What each component is called in the panel's "needs re-bake" line.
LABELS = {"lights": "lamps", "sky": "world", "occluders": "objects", "optics": "optics", "snow": "snow",
          "place": "snow layer's place"}
EARLIER = "baked by an earlier Firn"  # the bake recorded less than Firn records now: it cannot tell what changed
MAX_NAMED_OBJECTS = 3  # changed occluders named one by one; more are counted


def optics_digest(obj):
    try:
        volume = optics.volume_optics(obj.firn)
    except ValueError as error:
        return bake_inputs.digest(str(error))
    return bake_inputs.digest((round(volume.extinction_per_density, 9), tuple(round(a, 9) for a in volume.albedo),
                    round(volume.g, 9)))


def file_stamp(path):
    """(modification time ns, size) of a file, or None when it is missing."""
    try:
        stat = os.stat(path)
    except OSError:
        return None
    return stat.st_mtime_ns, stat.st_size


def file_digest(path):
    """Digest of a file as it is now (size and modification time; any thread)."""
    return bake_inputs.digest(file_stamp(path))


def snow_path(obj):
    return bpy.path.abspath(obj.data.filepath, library=obj.data.library)


def _placement(obj):
    return bake_inputs.rounded(v for row in obj.matrix_world for v in row)


def snow_digest(obj):
    return bake_inputs.digest((file_stamp(snow_path(obj)), _placement(obj)))


def place_digest(layer):
    """Where a snow layer stands: a spray's frames are baked where their layer stood (the objects around it shade
    them, and they stand still when it moves)."""
    return bake_inputs.digest(_placement(layer))


def fingerprint(context, obj, scene_signature=None):
    """{component: digest} of the bake's inputs now; `scene_signature` reuses one taken earlier."""
    parts = dict(scene_signature or bake_inputs.signature(context, obj))
    parts["optics"] = optics_digest(obj)
    parts["snow"] = snow_digest(obj)
    return parts


def store(obj, parts):
    obj.firn.bake_fingerprint = json.dumps(parts, sort_keys=True)


def stored(obj):
    text = obj.firn.bake_fingerprint
    if not text:
        return None
    try:
        return json.loads(text)
    except ValueError:
        return {}  # damaged: anything differs


def _changed_objects(then, now):
    """Labels of the occluders added, removed or changed; a fingerprint of an older Firn (one digest for all the
    objects) gives just "objects"."""
    if not isinstance(then, dict) or not isinstance(now, dict):
        return [LABELS["occluders"]]
    names = sorted(name for name in set(then) | set(now) if then.get(name) != now.get(name))
    shown = [f"object {name}" for name in names[:MAX_NAMED_OBJECTS]]
    if len(names) > MAX_NAMED_OBJECTS:
        shown.append(f"{len(names) - MAX_NAMED_OBJECTS} more objects")
    return shown


def changes(obj, context=None):
    """(state, [labels of what changed]) of a snow object against the live scene."""
    then = stored(obj)
    if then is None:
        return NONE, []
    context = context or bpy.context
    live = context.view_layer is not None and context.scene is not None  # not while loading
    if obj.type == "VOLUME" and obj.data.is_sequence:
        return _frame_changes(obj, context) if live else (BAKED, [])
    now = fingerprint(context, obj) if live else {"optics": optics_digest(obj), "snow": snow_digest(obj)}
    return _compare(then, now)


def _frame_changes(obj, context):
    """A sequence baked frame by frame: the marker of the frame shown now against the scene at that frame."""
    volume, frame = obj.data, context.scene.frame_current
    if not volume.frame_start <= frame < volume.frame_start + volume.frame_duration:
        return BAKED, []  # the Volume shows no frame now
    directory = cache.sequence_folder(volume)
    then = spray_files.read_marker(directory, frame)
    if then is None:
        return OUTDATED, [f"frame {frame} not lit"]
    source = obj.firn.spray.source
    tracked = os.path.exists(spray_files.frame_path(directory, frame, "snow"))  # simulated: the files are there
    snow, spray = spray_files.medium_paths(directory, frame, cache.volume_path(source.data) if source else "", tracked)
    now = dict(bake_inputs.signature(context, obj), optics=optics_digest(obj), snow=file_digest(snow),
               spray=file_digest(spray))
    if obj.firn.spray.role == "LIGHT" and source is not None:  # a layer lit frame by frame (spray/light.py)
        now.update(bake_inputs.signature(context, source), snow=snow_digest(source))
    elif source is not None:  # a spray's lumps or tracked snow
        now["place"] = place_digest(source)
    now["settings"] = then.get("settings")  # quality and seed are the bake's choice, not the scene's
    return _compare(then, now)


def _compare(then, now):
    changed = []
    for key in sorted(set(then) | set(now)):
        if key not in now or then.get(key) == now[key]:
            continue
        if then and key not in then:  # a fingerprint (not a damaged one) from before Firn recorded this
            if EARLIER not in changed:
                changed.append(EARLIER)
            continue
        changed.extend(_changed_objects(then.get(key), now[key]) if key == "occluders"
                       else [LABELS.get(key, key)])
    return (OUTDATED if changed else BAKED), changed


def state(obj):
    return changes(obj)[0]
