"""Add Snow Spray, Bake Sequence and Clear Snow Spray: snow thrown by the selected animated objects moving through
a snow layer, and the tracks they leave, simulated by the core frame by frame (docs/spray.md, "In Blender").

A spray is two Volume objects playing VDB sequences from one folder of the cache: "Snow Spray" (spray_####.vdb,
the lumps' density) and "<snow> Tracks" (snow_####.vdb, the snow with its tracks), which takes the snow layer's
place while the spray exists (the snow layer is hidden; Clear shows it again). Both are Firn snow (obj.firn.is_snow)
with the optics of the snow they came from, so the Snow Material panel and its render modes apply.
"""

import os

import bpy

from ..bake import operators as bake_operators, state as bake_state
from ..bake.inputs import occluder_objects
from ..common import cache, placement, scene_geometry
from ..common.core import firncore
from ..common.errors import UserError
from ..common.jobs import FirnJobMixin, scene_left, select_only
from ..common.modes import no_job_poll, object_mode_poll
from ..material import nodes as materials
from ..properties import (BAKE_QUALITY_ITEMS, CORE_SPRAY_SETTINGS, OPTICS_SETTINGS, SPRAY_PROPERTIES, active_snow_layer,
                          is_lit_sequence, is_spray)
from ..snow_layer import proxy
from ..snow_layer.operators import free_object_name, new_snow_object
from . import emitters as emitter_rectangles, files, light, snow_space
from .ui import ADD_LABEL, BAKE_LABEL, draw_spray_settings

FRAME_PROPERTIES = {
    "frame_start": bpy.props.IntProperty(
        name="Start", description="First frame: the snow as it was (default: the scene's start)", default=1, min=0),
    "frame_end": bpy.props.IntProperty(
        name="End", description="Last frame simulated (default: the scene's end)", default=250, min=0),
}


def frame_range(operator, scene, start=None):
    """The operator's frames; where the caller did not set them, `start` (else the scene's start) and the scene's
    end. UserError when the range holds fewer than two frames."""
    props = operator.properties
    if props.is_property_set("frame_start"):
        first = operator.frame_start
    else:
        first = scene.frame_start if start is None else start
    last = operator.frame_end if props.is_property_set("frame_end") else scene.frame_end
    if last <= first:
        raise UserError(f"End frame ({last}) must come after the start frame ({first}): the spray moves from one "
                        "frame to the next")
    return first, last


def core_settings(props):
    settings = firncore.SpraySettings(**{name: getattr(props, name) for name in CORE_SPRAY_SETTINGS})
    try:
        settings.validate()
    except ValueError as error:
        raise UserError(f"Snow Spray: {error}") from error
    return settings


def snow_file(snow):
    """The absolute path of a snow layer's VDB the core can read (density and surface), or UserError."""
    problem = cache.file_problem(snow.data)
    if problem is not None:
        raise UserError(f"'{snow.name}': {problem}. Regenerate it first")
    path = cache.volume_path(snow.data)
    try:
        names = firncore.grid_names(path)
    except (OSError, ValueError) as error:
        raise UserError(f"Cannot read the snow of '{snow.name}' ({error}): Regenerate it") from error
    if not {"density", "surface"} <= set(names):
        raise UserError(f"'{snow.name}' has no 'density' and 'surface' grids: it is not a Firn snow layer")
    return path


def _static_obstacles(context, emitters, first, last):
    """The objects lumps land on: the rendered, shadow-casting ones (the bake's occluders) less the emitters and
    less whatever moves between the first and the last frame (a skier's body): the core's obstacles stand still,
    and one kept where it stood at the first frame would stop lumps in mid-air later."""
    scene = context.scene
    candidates = [obj for obj in occluder_objects(context.view_layer) if obj not in emitters]
    scene.frame_set(first)
    placed = {obj.name: obj.matrix_world.copy() for obj in candidates}
    scene.frame_set(last)
    return [obj for obj in candidates if obj.matrix_world == placed[obj.name]]


def gather_inputs(context, props, snow, emitters, frames, directory):
    """Everything the core needs for one spray sequence, read on the main thread (the worker never touches bpy)."""
    first, last = frames
    rectangles = emitter_rectangles.rectangles(context, emitters, props, first, last)
    scene = context.scene
    current = scene.frame_current
    try:
        obstacles = _static_obstacles(context, emitters, first, last)
        scene.frame_set(first)
        objects = scene_geometry.world_triangles(obstacles, context.evaluated_depsgraph_get())
    finally:
        scene.frame_set(current)  # also brings the snow's matrix_world up to date
    space = snow_space.snow_space(snow, scene)
    settings = core_settings(props)
    settings.down = snow_space.down_in(space)
    cache.check_writable(os.path.join(directory, "spray.vdb"))
    return {
        "snow_path": snow_file(snow), "emitters": snow_space.rectangles_in(space, rectangles),
        "directory": directory, "objects": snow_space.triangles_in(space, objects),
        "fps": scene.render.fps / scene.render.fps_base, "first": first, "last": last, "settings": settings,
    }


def simulate(inputs, progress):
    """Worker thread: the core simulates the frames not yet on disk (it resumes), then every frame gets its tracked
    snow file (files.fill_tracked_snow). No bpy here."""
    run = cache.core_write(firncore.simulate_spray, inputs["snow_path"], inputs["emitters"], inputs["directory"],
                           inputs["fps"], inputs["first"], inputs["settings"], inputs["objects"], progress)
    if run["snow_frames"]:
        files.fill_tracked_snow(inputs["directory"], inputs["snow_path"], inputs["first"], inputs["last"],
                                run["snow_frames"])
    return run


def summary(inputs, run):
    frames = inputs["last"] - inputs["first"] + 1
    resumed = f", resumed after frame {run['resumed_after']}" if run["resumed_after"] is not None else ""
    simulated = f"{frames} frames ({len(run['frames_written'])} simulated{resumed})"
    if not run["frames_written"]:  # nothing ran: the core has no lump counts to give
        return f"{simulated}; tracks in {len(run['snow_frames'])} frames"
    return (f"{simulated}; last frame: {run['flying']:,} lumps flying, {run['resting']:,} resting; tracks in "
            f"{len(run['snow_frames'])} frames")


def play_sequence(obj, folder, kind, first, last):
    """Points a Volume at the `kind` ("spray", "snow", "lit", ...) files of a spray folder (absolute) as a
    sequence: scene frame f plays the file of frame f, held before the first and after the last. The path is
    stored as the .blend stands when the job ends (cache.stored_path), or absolute where the user made it so."""
    volume = obj.data
    path = files.frame_path(folder, first, kind)
    absolute = volume.filepath and not volume.filepath.startswith("//")  # Make Paths Absolute, a farm's setup
    volume.filepath = path if absolute else cache.stored_path(path)
    volume.is_sequence = True
    volume.frame_start = first
    volume.frame_duration = last - first + 1
    volume.frame_offset = first - 1  # Blender reads file number (scene frame - frame_start + 1) + frame_offset
    volume.sequence_mode = "EXTEND"
    cache.file_fixed(volume)
    cache.reload_grids(volume)


def show_snow(snow, shown):
    """The snow layer is hidden while its tracked snow plays in its place (viewport and render), and shown again
    by Clear; its viewport proxy follows its own Display and render settings."""
    snow.hide_viewport = snow.hide_render = not shown
    proxy_object = proxy.proxy_of(snow)
    if proxy_object is None:
        return
    if shown:
        proxy.apply_display(snow)
        proxy.apply_render_surface(snow)
    else:
        proxy_object.hide_viewport = proxy_object.hide_render = True


def sequence_objects(folder):
    """The spray Volumes (spray and tracks) that play files of the spray folder `folder` (absolute)."""
    return [obj for obj in bpy.data.objects if is_spray(obj)
            and os.path.normpath(cache.sequence_folder(obj.data)) == os.path.normpath(folder)]


def new_sequence_object(context, name, role, snow, frames):
    """A Volume of Firn snow for a sequence made from the snow layer `snow` (`role` SPRAY, TRACKS or LIGHT), with
    its optics. A child of the snow layer, drawn in its space: its files are in the snow's file space
    (snow_space.py), it moves with the layer and stays put if the layer is deleted."""
    obj = new_snow_object(context, name)
    placement.follow(obj, snow)
    for setting in OPTICS_SETTINGS + ("render_mode",):
        setattr(obj.firn, setting, getattr(snow.firn, setting))  # its own from now on: its Snow Material panel
    obj.firn.voxel_size = snow.firn.voxel_size
    obj.firn.display = "VOLUME"  # no viewport proxy: the volume itself shows
    record = obj.firn.spray
    record.role, record.source = role, snow
    record.frame_start, record.frame_end = frames
    return obj


def _new_spray_object(context, name, role, snow, props, emitters, frames):
    """A spray's Volume (new_sequence_object) with the settings it was made with: Bake Sequence makes it again
    from them."""
    obj = new_sequence_object(context, name, role, snow, frames)
    record = obj.firn.spray
    for setting in SPRAY_PROPERTIES:
        setattr(record, setting, getattr(props, setting))
    for emitter in emitters:
        record.emitters.add().object = emitter  # None: an emitter deleted while the spray was simulated
    return obj


def _emitter_objects(context, snow):
    emitters = [obj for obj in context.selected_objects if obj != snow and scene_geometry.is_mesh_like(obj)]
    if not emitters:
        raise UserError("Select the moving objects that throw snow (meshes: skis, boards, wheels), then the snow "
                        "layer they move through last, so that it is active")
    return emitters


class FIRN_OT_add_snow_spray(FirnJobMixin, bpy.types.Operator):
    """Snow thrown by the selected animated objects moving through the active snow layer, and the tracks they
    leave: a Volume sequence per frame range"""

    bl_idname = "firn.add_snow_spray"
    bl_label = "Add Snow Spray"
    bl_options = {"REGISTER", "UNDO"}
    __annotations__ = dict(FRAME_PROPERTIES, **SPRAY_PROPERTIES)
    job_label = ADD_LABEL
    job_passes_events = True

    @classmethod
    def poll(cls, context):
        return object_mode_poll(cls, context) and no_job_poll(cls)

    def draw(self, _context):
        draw_spray_settings(self.layout, self, (*FRAME_PROPERTIES, *SPRAY_PROPERTIES))

    def prepare(self, context):
        snow = active_snow_layer(context)
        if snow is None:
            raise UserError("Make a Firn snow layer the active object (select it last): the snow the selected "
                            "objects move through")
        emitters = _emitter_objects(context, snow)
        if self.cut_tracks and any(is_lit_sequence(obj) and obj.firn.spray.source == snow for obj in bpy.data.objects):
            raise UserError(f"'{snow.name}' is lit frame by frame (Bake Light Sequence): Clear Light Sequence first "
                            "(Bake Sequence lights the tracked snow frame by frame), or turn Cut Tracks off")
        frames = frame_range(self, context.scene)
        name = free_object_name("Snow Spray")
        directory = cache.spray_folder(name)[0]
        inputs = gather_inputs(context, self, snow, emitters, frames, directory)
        return dict(inputs, name=name, snow=snow.name, emitter_names=[obj.name for obj in emitters],
                    scene=context.scene.name)

    compute = staticmethod(simulate)

    def apply(self, context, inputs, run):
        snow = bpy.data.objects.get(inputs["snow"])  # the user kept working during the simulation
        if scene_left(self, context, inputs["scene"]):
            return
        if snow is None:
            self.report({"WARNING"}, f"'{inputs['snow']}' was deleted or renamed during the simulation: no spray was "
                                     f"added (its frames are in {inputs['directory']})")
            return
        emitters = [bpy.data.objects.get(name) for name in inputs["emitter_names"]]
        if None in emitters:  # kept as an empty slot: Bake Sequence then says it cannot simulate the spray again
            self.report({"WARNING"}, "An emitter was deleted or renamed during the simulation: Bake Sequence leaves "
                                     "this spray out while it lacks it (Clear it, then Add Snow Spray again)")
        frames = inputs["first"], inputs["last"]
        spray = _new_spray_object(context, inputs["name"], "SPRAY", snow, self, emitters, frames)
        spray.firn.mean_density = self.lump_density
        spray.firn.spray.summary = summary(inputs, run)
        play_sequence(spray, inputs["directory"], "spray", *frames)
        materials.ensure_snow_material(spray)
        if run["snow_frames"]:
            tracks = _new_spray_object(context, free_object_name(f"{snow.name} Tracks"), "TRACKS", snow, self,
                                       emitters, frames)
            tracks.firn.mean_density = snow.firn.mean_density
            play_sequence(tracks, inputs["directory"], "snow", *frames)
            materials.ensure_snow_material(tracks)
            show_snow(snow, False)
        select_only(context, spray)
        self.report({"INFO"}, f"Snow Spray: {spray.firn.spray.summary}")


def baked_frames(operator, record):
    """(simulated, lit) frame ranges of Bake Sequence for one spray: the frames asked for (default: the spray's
    own range) are lit; the simulation runs from the spray's first frame to the last frame asked
    for, at least to the end it already had (a render-farm node asked for one frame never shortens it)."""
    props = operator.properties
    start = operator.frame_start if props.is_property_set("frame_start") else record.frame_start
    end = operator.frame_end if props.is_property_set("frame_end") else record.frame_end
    if start < record.frame_start:
        raise UserError(f"The spray starts at frame {record.frame_start}: Clear it and Add Snow Spray from frame "
                        f"{start} to simulate from there")
    if end < start:
        raise UserError(f"End frame ({end}) must not come before the start frame ({start})")
    simulated = record.frame_start, max(end, record.frame_end, record.frame_start + 1)
    return simulated, (start, end)


def _tracks_of(spray):
    directory = cache.sequence_folder(spray.data)
    return next((obj for obj in sequence_objects(directory) if obj.firn.spray.role == "TRACKS"), None)


def _light_jobs(operator, context, spray, lit_frames):
    """The per-frame light jobs of a spray's lumps and tracked snow (spray/light.py), or [] with Bake Light off."""
    tracks = _tracks_of(spray)
    if not operator.light:
        return None, []
    return (tracks.name if tracks is not None else None,
            light.gather(context, spray, tracks, range(lit_frames[0], lit_frames[1] + 1), operator.quality,
                         operator.seed))


class FIRN_OT_bake_sequence(FirnJobMixin, bpy.types.Operator):
    """Simulate every Snow Spray of the scene over a frame range and bake the light of its lumps and tracked snow
    frame by frame: frames already on disk for the same scene and settings are kept (an interrupted bake resumes; render
    farm nodes may each bake their own frames)"""

    bl_idname = "firn.bake_sequence"
    bl_label = "Bake Sequence"
    bl_options = {"REGISTER", "UNDO"}
    __annotations__ = dict(
        FRAME_PROPERTIES,
        light=bpy.props.BoolProperty(
            name="Bake Light", default=True,
            description="Bake the light of the thrown lumps and the tracked snow at every frame, lit together "
                        "(Bake Scattering, frame by frame)"),
        quality=bpy.props.EnumProperty(name="Quality", items=BAKE_QUALITY_ITEMS, default="FINAL"),
        seed=bpy.props.IntProperty(name="Light Seed", description="Same scene and seed, same bake", default=0,
                                   min=0),
    )
    job_label = BAKE_LABEL
    job_passes_events = True

    @classmethod
    def poll(cls, context):
        if not any(obj.firn.spray.role == "SPRAY" for obj in context.scene.objects):
            cls.poll_message_set("The scene has no Snow Spray: use Add Snow Spray first")
            return False
        return no_job_poll(cls)

    def prepare(self, context):
        jobs, broken = [], []
        for spray in [obj for obj in context.scene.objects if obj.firn.spray.role == "SPRAY"]:
            record = spray.firn.spray
            snow = record.source
            emitters = [item.object for item in record.emitters]
            if snow is None or None in emitters:  # it cannot be simulated again; the others can
                broken.append(f"'{spray.name}': its snow layer or one of its emitters was deleted: Clear it and Add "
                              "Snow Spray again")
                continue
            for obj in (spray, _tracks_of(spray)):  # also a spray saved before they followed their snow layer
                if obj is not None:
                    placement.follow(obj, snow)  # where the layer stands now: they stay there if it is deleted
            simulated, lit = baked_frames(self, record)
            directory = cache.sequence_folder(spray.data)
            inputs = gather_inputs(context, record, snow, emitters, simulated, directory)
            tracks, frames = _light_jobs(self, context, spray, lit)
            jobs.append(dict(inputs, name=spray.name, tracks=tracks, lit=lit, frames=frames))
        if broken and not jobs:
            raise UserError("; ".join(broken))
        worlds = light.world_requests(context.scene, [frame for job in jobs for frame in job["frames"]])
        return {"jobs": jobs, "current": 0, "worlds": worlds, "quality": self.quality, "seed": self.seed,
                "scene": context.scene.name, "left_out": broken}

    def job_status(self, inputs, progress):
        jobs = inputs["jobs"]
        part = f"{jobs[inputs['current']]['name']} ({inputs['current'] + 1}/{len(jobs)}) " if len(jobs) > 1 else ""
        return part + progress.stage

    @staticmethod
    def compute(inputs, progress):
        """Worker thread: every spray's simulation, then the light of the frames whose lit file is missing or was
        made from other snow (the simulation may have rewritten it), after the worlds they need."""
        try:
            runs = []
            for index, job in enumerate(inputs["jobs"]):
                inputs["current"] = index
                runs.append(simulate(job, progress))
            todos = [FIRN_OT_bake_sequence._unlit(job) for job in inputs["jobs"]]
            light.light_worlds(inputs["worlds"], [frame for todo in todos for frame in todo], progress)
            for index, (job, todo) in enumerate(zip(inputs["jobs"], todos)):
                inputs["current"] = index
                job["processor_seconds"] = light.bake_frames(todo, inputs["quality"], inputs["seed"], progress)
            return runs
        finally:
            light.discard_worlds(inputs["worlds"])  # a simulation failed or was cancelled: the worlds are not needed

    @staticmethod
    def _unlit(job):
        """The job's frames whose lit files are missing or were baked from other files than the simulation left."""
        todo = []
        for frame in job["frames"]:
            light.read_files(frame)  # as the simulation left them
            if not light.is_lit(frame):
                todo.append(frame)
        job["baked"] = [frame["frame"] for frame in todo]
        return todo

    def apply(self, context, inputs, runs):
        baked_scene = bpy.data.scenes.get(inputs["scene"], context.scene)  # whichever the user shows now
        for job, run in zip(inputs["jobs"], runs):
            spray = bpy.data.objects.get(job["name"])  # the user may have deleted it during the bake
            if spray is not None:
                spray.firn.spray.summary = summary(job, run)
                self.report({"INFO"}, f"{spray.name}: {spray.firn.spray.summary}")
            for obj in sequence_objects(job["directory"]):
                obj.firn.spray.frame_start, obj.firn.spray.frame_end = job["first"], job["last"]
                unlit, lit = ("spray", "lit_spray") if obj.firn.spray.role == "SPRAY" else ("snow", "lit")
                kind = lit if self._plays_light(obj, job, lit) else unlit
                play_sequence(obj, cache.sequence_folder(obj.data), kind, job["first"], job["last"])
                if kind == lit:
                    self._adopt_light(baked_scene, obj, job)
                elif not self.light:  # Bake Light off: the lumps and the tracked snow render unlit
                    obj.firn.bake_fingerprint = obj.firn.bake_summary = ""
                    materials.ensure_snow_material(obj)
        for message in inputs["left_out"]:  # last: the sprays' reports would hide it
            self.report({"WARNING"}, f"{message} (left out of this bake)")

    def _plays_light(self, obj, job, kind):
        """A spray or its tracked snow plays its lit files (`kind`) when every frame has one, or when only some
        frames were asked for (a render-farm node): then the others are said to be missing."""
        if not self.light or (kind == "lit" and job["tracks"] is None):
            return False
        first, last = job["lit"]
        if light.all_lit(job["directory"], job["first"], job["last"], kind):
            return True
        if (first, last) != (job["first"], job["last"]) and light.all_lit(job["directory"], first, last, kind):
            self.report({"WARNING"}, f"'{obj.name}': frames outside {first}-{last} have no baked light yet and "
                                     "show nothing until they are baked")
            return True
        return False

    def _adopt_light(self, scene, obj, job):
        frames, seconds = job["baked"], job["processor_seconds"]
        bake_operators.keep_baked_optics(obj.firn, bake_operators.volume_optics_of(obj))
        # What a frame cost (docs/user-guide.md: some 28 processor s with occluders at Final, 7 at Draft)
        cost = f"; {sum(seconds) / len(seconds):.1f} processor s a frame" if seconds else ""
        obj.firn.bake_summary = (f"{self.quality.title()} light, frames {job['lit'][0]}-{job['lit'][1]} "
                                 f"({len(frames)} baked now, the others already were{cost})")
        bake_state.store(obj, {"sequence": light.sequence_digest(job["directory"], job["first"], job["last"])})
        materials.ensure_snow_material(obj)
        if materials.material_form(obj) == "BAKED_SCATTER":
            changed = bake_operators.scatter_render_settings(scene)
            if changed:
                self.report({"WARNING"}, f"Changed for the thin snow of '{obj.name}': " + "; ".join(changed))


def remove_sequence(folder):
    """Deletes a sequence's folder and the Volumes that play it; the snow layer shows again where its tracked or lit
    snow played in its place. Returns their names; UserError, with nothing removed, when the files cannot be."""
    objects = sequence_objects(folder)
    try:
        files.remove_sequence(folder)
    except OSError as error:
        raise UserError(f"Cannot remove the files in {folder} ({error}); nothing was removed") from error
    names = []
    for obj in objects:
        snow = obj.firn.spray.source
        if obj.firn.spray.role in ("TRACKS", "LIGHT") and snow is not None:
            show_snow(snow, True)
        names.append(obj.name)
        volume = obj.data
        bpy.data.objects.remove(obj)
        if volume.users == 0:
            bpy.data.volumes.remove(volume)
    return names


def clear_sequence(operator, obj):
    """Clear Snow Spray's and Clear Light Sequence's work: obj's sequence removed (remove_sequence) and reported."""
    try:
        names = remove_sequence(cache.sequence_folder(obj.data))
    except UserError as error:
        operator.report({"ERROR"}, str(error))
        return {"CANCELLED"}
    operator.report({"INFO"}, f"Removed {', '.join(names)} and their files")
    return {"FINISHED"}


class FIRN_OT_clear_snow_spray(bpy.types.Operator):
    """Remove the active Snow Spray, its tracked snow and their files; the snow layer shows again"""

    bl_idname = "firn.clear_snow_spray"
    bl_label = "Clear Snow Spray"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not is_spray(context.object) or is_lit_sequence(context.object):
            cls.poll_message_set("Select a Snow Spray (or its Tracks)")
            return False
        return no_job_poll(cls)

    def execute(self, context):
        return clear_sequence(self, context.object)


classes = (FIRN_OT_add_snow_spray, FIRN_OT_bake_sequence, FIRN_OT_clear_snow_spray)
