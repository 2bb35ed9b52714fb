"""Bake Light Sequence and Clear Light Sequence: a snow layer's light baked frame by frame, for lamps, a sun, a
world or objects that move (docs/user-guide.md "Light that moves").

The layer's own file is baked at each frame into lit_####.vdb of a cache folder, each with its marker (what the
frame was baked from), as Bake Sequence lights a spray's tracked snow (spray/light.py). A Volume "<snow> Lit" plays
the frames in the layer's place: the layer is hidden until Clear Light Sequence removes the Lit Volume and its
files. A frame whose marker matches the scene is kept, so an interrupted bake resumes and render-farm nodes bake
their own frames into one folder. The snow is not animated: Regenerate it and the frames need baking again.
"""

import os
import shutil

import bpy

from ..common import cache
from ..common.errors import UserError
from ..common.jobs import FirnJobMixin, scene_left, select_only
from ..common.modes import no_job_poll, object_mode_poll
from ..material import nodes as materials
from ..properties import BAKE_QUALITY_ITEMS, active_snow_layer, is_lit_sequence
from ..snow_layer.operators import free_object_name
from ..spray import files, light
from ..spray.operators import clear_sequence, new_sequence_object, play_sequence, show_snow
from . import state as bake_state
from .operators import BAKE_LABEL, check_volume, keep_baked_optics, scatter_render_settings


def lit_sequence_of(snow):
    """The Volume that plays a snow layer's lit frames, or None."""
    return next((obj for obj in bpy.data.objects if is_lit_sequence(obj) and obj.firn.spray.source == snow), None)


def _layer(context):
    """The snow layer to light: the active snow layer, or the one whose lit frames the active object plays."""
    obj = context.object
    if is_lit_sequence(obj):
        if obj.firn.spray.source is None:
            raise UserError(f"'{obj.name}': its snow layer was deleted: Clear Light Sequence")
        return obj.firn.spray.source
    return active_snow_layer(context)


# A lit frame's file over its snow file's size: the snow's grids and six source grids (the car sample's 2.7M voxels:
# 68.5 MB against 23.9 MB, 2.9×); the disk check's estimate, with a margin.
_LIT_SIZE_RATIO = 4


def _check_disk(directory, snow_path, frames):
    """UserError, before any work, when the frames not yet lit would not fit on the cache's disk."""
    missing = sum(not os.path.exists(files.frame_path(directory, frame, "lit")) for frame in frames)
    needed = missing * _LIT_SIZE_RATIO * os.path.getsize(snow_path)  # bytes
    free = shutil.disk_usage(directory).free
    if needed > free:
        raise UserError(f"{missing} frames of light need about {needed / 1e9:.1f} GB and {directory} has "
                        f"{free / 1e9:.1f} GB free: bake fewer frames (Start, End) or make room")


def _check_no_tracks(snow):
    """UserError when a Snow Spray's tracked snow plays in the layer's place: both would render."""
    if any(obj.firn.spray.role == "TRACKS" and obj.firn.spray.source == snow for obj in bpy.data.objects):
        raise UserError(f"'{snow.name}' has a Snow Spray's tracks playing in its place: Bake Sequence (Snow Spray "
                        "panel) lights the tracked snow frame by frame")


def _frames(operator, scene):
    """The operator's frames (default: the scene's range), or UserError."""
    props = operator.properties
    first = operator.frame_start if props.is_property_set("frame_start") else scene.frame_start
    last = operator.frame_end if props.is_property_set("frame_end") else scene.frame_end
    if last < first:
        raise UserError(f"End frame ({last}) must not come before the start frame ({first})")
    return first, last


class FIRN_OT_bake_light_sequence(FirnJobMixin, bpy.types.Operator):
    """Bake the light of the active snow layer at every frame of a range, for lamps, a sun, a world or objects that
    move: a Volume plays the lit frames in the layer's place. Frames already baked from the same scene are kept
    (an interrupted bake resumes; render-farm nodes may each bake their own frames)"""

    bl_idname = "firn.bake_light_sequence"
    bl_label = "Bake Light Sequence"
    bl_options = {"REGISTER", "UNDO"}
    job_label = BAKE_LABEL
    job_passes_events = True

    frame_start: bpy.props.IntProperty(name="Start", description="First frame (default: the scene's start)",
                                       default=1, min=0)
    frame_end: bpy.props.IntProperty(name="End", description="Last frame (default: the scene's end)", default=250,
                                     min=0)
    quality: bpy.props.EnumProperty(name="Quality", items=BAKE_QUALITY_ITEMS, default="FINAL")
    seed: bpy.props.IntProperty(name="Seed", description="Same scene and seed, same bake", default=0, min=0)

    @classmethod
    def poll(cls, context):
        if not object_mode_poll(cls, context):
            return False
        if not no_job_poll(cls):
            return False
        obj = context.object
        if not is_lit_sequence(obj) and active_snow_layer(context) is None:
            cls.poll_message_set("Select a snow layer (made by Add Snow Layer)")
            return False
        return True

    def prepare(self, context):
        snow = _layer(context)
        if snow is None:
            raise UserError("Make a Firn snow layer the active object: the snow to light frame by frame")
        snow_path = check_volume(snow)
        _check_no_tracks(snow)
        first, last = _frames(self, context.scene)
        lit = lit_sequence_of(snow)
        if lit is not None:
            name, directory = lit.name, cache.sequence_folder(lit.data)
            shown = min(first, lit.firn.spray.frame_start), max(last, lit.firn.spray.frame_end)
        else:
            name = free_object_name(f"{snow.name} Lit")
            directory = cache.spray_folder(name)[0]
            shown = first, last
        cache.check_writable(os.path.join(directory, "lit.vdb"))
        _check_disk(directory, snow_path, range(first, last + 1))
        # The Lit Volume's own optics once it exists (its Snow Material panel), the layer's before.
        jobs = light.gather_layer(context, snow, lit or snow, range(first, last + 1), directory, self.quality,
                                  self.seed)
        return {"jobs": jobs, "worlds": light.world_requests(context.scene, jobs), "snow": snow.name, "name": name,
                "directory": directory, "frames": (first, last), "shown": shown,
                "quality": self.quality, "seed": self.seed, "scene": context.scene.name}

    def job_status(self, inputs, progress):
        todo = inputs.get("todo")
        if not todo:
            return progress.stage
        return f"frame {todo[inputs['current']]} ({inputs['current'] + 1}/{len(todo)}) {progress.stage}"

    @staticmethod
    def compute(inputs, progress):
        """Worker thread: the worlds the frames not yet lit from this scene need, then those frames."""
        todo = [job for job in inputs["jobs"] if not light.is_lit(job)]
        light.light_worlds(inputs["worlds"], todo, progress)
        inputs["current"], inputs["todo"] = 0, [job["frame"] for job in todo]
        return light.bake_frames(todo, inputs["quality"], inputs["seed"], progress,
                                 on_frame=lambda index: inputs.update(current=index))

    def apply(self, context, inputs, seconds):
        snow = bpy.data.objects.get(inputs["snow"])  # the user kept working during the bake
        if scene_left(self, context, inputs["scene"]):
            return
        if snow is None:
            self.report({"WARNING"}, f"'{inputs['snow']}' was deleted or renamed during the bake: its lit frames are "
                                     f"in {inputs['directory']}")
            return
        lit = _lit_volume(context, snow, inputs)
        first, last = inputs["shown"]
        play_sequence(lit, inputs["directory"], "lit", first, last)
        keep_baked_optics(lit.firn, inputs["jobs"][0]["optics"])
        cost = f"; {sum(seconds) / len(seconds):.1f} processor s a frame" if seconds else ""
        lit.firn.bake_summary = (f"{inputs['quality'].title()} light, frames {first}-{last} "
                                 f"({len(inputs['todo'])} baked now, the others already were{cost})")
        bake_state.store(lit, {"sequence": light.sequence_digest(inputs["directory"], first, last)})
        materials.ensure_snow_material(lit)
        show_snow(snow, False)
        self._report_missing(lit, inputs["directory"], first, last)
        if materials.material_form(lit) == "BAKED_SCATTER":
            changed = scatter_render_settings(context.scene)
            if changed:
                self.report({"WARNING"}, f"Changed for the thin snow of '{lit.name}': " + "; ".join(changed))
        select_only(context, lit)
        frames = inputs["frames"]
        self.report({"INFO"}, f"{lit.name}: frames {frames[0]}-{frames[1]} lit ({len(inputs['todo'])} baked now)")

    def _report_missing(self, lit, directory, first, last):
        """Blender plays a sequence whose files are missing as nothing at those frames: say which."""
        missing = [frame for frame in range(first, last + 1)
                   if not os.path.exists(files.frame_path(directory, frame, "lit"))]
        if missing:
            self.report({"WARNING"}, f"'{lit.name}': frames {missing[0]}-{missing[-1]} have no baked light yet "
                                     "and show nothing until they are baked")


def _lit_volume(context, snow, inputs):
    """The layer's Lit Volume, made with the layer's optics and mean density the first time (its own from then
    on), playing frames inputs["shown"]."""
    first, last = inputs["shown"]
    lit = lit_sequence_of(snow)
    if lit is None:
        lit = new_sequence_object(context, inputs["name"], "LIGHT", snow, (first, last))
        lit.firn.mean_density = snow.firn.mean_density
    lit.firn.spray.frame_start, lit.firn.spray.frame_end = first, last
    return lit


class FIRN_OT_clear_light_sequence(bpy.types.Operator):
    """Remove the snow layer's lit frames and their files: the snow layer shows again, with its own bake if it had
    one"""

    bl_idname = "firn.clear_light_sequence"
    bl_label = "Clear Light Sequence"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not is_lit_sequence(context.object):
            cls.poll_message_set("Select the Lit Volume made by Bake Light Sequence")
            return False
        return no_job_poll(cls)

    def execute(self, context):
        return clear_sequence(self, context.object)


classes = (FIRN_OT_bake_light_sequence, FIRN_OT_clear_light_sequence)
