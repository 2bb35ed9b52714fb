"""Bake Scattering and Clear Bake: the light inside the snow, computed by the core from the scene's suns, sky and
occluders, and the snow's material switched to render it (docs/user-guide.md "Bake Scattering").

The core rewrites a snow file atomically; to keep the previous bake intact when a bake of several objects is
cancelled or fails half way, each object is baked into a staged copy beside its file (the core reads the file
and writes the copy), and the copies replace
the files only once every bake has finished (apply, main thread). Cancel: the staged copies are deleted, no file
or material is touched.
"""

import math
import os
import time

import bpy

from ..common import cache
from ..common.core import firncore
from ..common.errors import UserError
from ..common.jobs import FirnJobMixin
from ..common.modes import no_job_poll, object_mode_poll
from ..material import nodes as materials, optics
from ..properties import BAKE_QUALITY_ITEMS, is_lit_sequence
from ..snow_layer import proxy
from . import inputs as bake_inputs, state as bake_state

BAKE_LABEL = "Bake Scattering"
REBUILD_ADVICE = ("Regenerate the snow (Firn Snow Layer panel) to write it again, or put the .blend's firn_cache "
                  "folder back beside it and reopen")
_STAGED_SUFFIX = ".firn-bake.vdb"
_SCATTER_BOUNCES = 32  # Cycles' volume bounces for snow it scatters (scatter_render_settings)


def bake_targets(context):
    """Volume objects to bake: the selected ones and the active one."""
    objects = list(context.selected_objects)
    if context.active_object is not None and context.active_object not in objects:
        objects.append(context.active_object)
    return [obj for obj in objects if obj.type == "VOLUME"]


def core_light(inputs):
    """BakeInputs as the core's bake calls take them: suns, lamps, sky and occluders keyword arguments."""
    sky = inputs.sky
    return dict(
        suns=[firncore.SunLight(sun.direction, sun.irradiance, sun.angular_diameter) for sun in inputs.suns],
        lamps=[firncore.Lamp(lamp.shape, lamp.position, lamp.emission, axis=lamp.axis, tangent=lamp.tangent,
                             radius=lamp.radius, spot_angle=lamp.spot_angle, spot_blend=lamp.spot_blend,
                             size=lamp.size) for lamp in inputs.lamps],
        sky=firncore.Sky(radiance=tuple(sky.radiance), map=sky.map),  # map: (H, W, 3), rows bottom to top
        occluders=[(o.vertices, o.triangles, o.albedo) for o in inputs.occluders])


def core_bake(path, output, volume_optics, inputs, quality, seed, progress):
    """The one call into the core's bake (cpp/python/bind_transport.cpp): it reads `path` once, bakes its `density`
    and writes its grids with the baked ones added to `output`, atomically; returns its stats. Raises
    firncore.ReadError when `path` cannot be read, another OSError when `output` cannot be written."""
    return firncore.bake(path, volume_optics, output_path=output, quality=quality, seed=seed, progress=progress,
                  **core_light(inputs))


def sequence_advice(obj):
    """What bakes or clears the light of a Volume sequence instead of Bake Scattering and Clear Bake."""
    if is_lit_sequence(obj):
        return "Bake Light Sequence bakes its light again, Clear Light Sequence removes it (Firn Bake panel)"
    return "bake its light frame by frame with Bake Sequence (Snow Spray panel); with Bake Light off it clears it"


def check_volume(obj):
    """The absolute path of a Volume's file that Firn can bake, or UserError saying why not."""
    volume = obj.data
    if obj.library or volume.library:
        raise UserError(f"'{obj.name}' is linked from a library: bake it in its own file")
    if volume.packed_file is not None:
        raise UserError(f"'{obj.name}' has its volume packed into the .blend: unpack it to bake")
    if volume.is_sequence:
        raise UserError(f"'{obj.name}' is a volume sequence: {sequence_advice(obj)}")
    problem = cache.file_problem(volume)
    if problem is not None:
        raise UserError(f"'{obj.name}': {problem}. {REBUILD_ADVICE}")
    path = bake_state.snow_path(obj)
    try:
        names = firncore.grid_names(path)
    except (OSError, ValueError) as error:
        raise UserError(f"Cannot read the volume of '{obj.name}' ({error}). {REBUILD_ADVICE}") from error
    cache.check_writable(path)  # the staged copy goes beside it
    if "density" not in names:
        raise UserError(f"'{obj.name}' has no 'density' grid to bake")
    return path


def _bake_job(job, quality, seed, progress):
    """Worker thread: bakes one snow file into its staged copy. The main thread only checked the file's header;
    the core's one full read says when the file is damaged (its ReadError), apart from a failed write."""
    try:
        cache.core_write(core_bake, job["path"], job["staged"], job["optics"], job["inputs"], quality, seed,
                         progress)
    except firncore.ReadError as error:
        raise UserError(f"Cannot read the volume of '{job['name']}' ({error}). {REBUILD_ADVICE}") from error
    job["proxy_colours"] = proxy.baked_colours(job["staged"], job["proxy_points"])


def render_world(inputs, progress):
    """Any thread: computes a Nishita world in the core, or renders any other world (world_probe: a child
    Blender off the main thread), and completes the inputs of the jobs whose sky waits for it; then the job's
    status moves on to the bake."""
    world = inputs["world"]
    if world is None:
        return
    if not world.prepare(cancelled=lambda: progress.cancelled):
        raise firncore.Cancelled("cancelled")
    for job in inputs["jobs"]:
        if job["inputs"].sky is None:
            if progress.cancelled:
                raise firncore.Cancelled("cancelled")
            bake_inputs.add_world_light(job["inputs"], world)
    inputs["world"] = None


def volume_optics_of(obj):
    """The object's firncore.VolumeOptics, or UserError naming the bad setting."""
    try:
        return optics.volume_optics(obj.firn)
    except ValueError as error:
        raise UserError(f"'{obj.name}': {error} (Snow Material panel)") from error


def _render_settings(obj):
    """Sets the Volume data settings baked snow needs and returns what changed, to be reported: full precision
    (half floats round values to 3 digits) and no clipping (it cuts thin, low-density fringes)."""
    render = obj.data.render
    changed = []
    if render.precision != "FULL":
        changed.append(f"precision {render.precision.title()} → Full")
        render.precision = "FULL"
    if render.clipping != 0.0:
        changed.append(f"clipping {render.clipping:g} → 0")
        render.clipping = 0.0
    return [f"'{obj.name}' volume {change}" for change in changed]


def scatter_render_settings(scene):
    """Sets what Cycles needs to scatter thin snow (material form BAKED_SCATTER) and returns what changed, to be
    reported: volume bounces >= 32 (forward snow turns the light by a few scatterings: -27 % at 4, -0.7 % at 16,
    docs/benchmarks.md, thin-ring; 16 -> 32 brightens ball_thin +0.43 %, 32 -> 64 +0.001 %, cycles-bounce; for no
    render time measurable within a few per cent, tidy-63) and total bounces as many, which cap them."""
    cycles = getattr(scene, "cycles", None)
    changed = []
    if cycles is None:
        return changed
    for name, label in (("volume_bounces", "volume bounces"), ("max_bounces", "total bounces")):
        if getattr(cycles, name) < _SCATTER_BOUNCES:
            changed.append(f"{label} {getattr(cycles, name)} → {_SCATTER_BOUNCES}")
            setattr(cycles, name, _SCATTER_BOUNCES)
    return [f"scene '{scene.name}' {change}" for change in changed]


def _clamp_warning(scene, jobs, scattering=False):
    """Baked snow lights its neighbours through their indirect rays, which Cycles' Clamp Indirect limits: say so
    when the snow may be brighter than the clamp (white snow sends back at most (E_sun + pi L_sky) / pi), or when
    Cycles scatters thin snow (`scattering`): the forward phase function's sun samples pass any usual clamp, so
    it darkens that snow too (cycles-volumes.md: g 0.87 peaks at 8.8 /sr)."""
    clamp = getattr(getattr(scene, "cycles", None), "sample_clamp_indirect", 0.0)
    if clamp <= 0.0:
        return None
    if scattering:
        return (f"Clamp Indirect ({clamp:g}) darkens the thin snow Cycles scatters (Scatter Thin Snow) and cuts the "
                "light the snow throws on nearby objects: set 0 (Render Properties > Light Paths > Clamping)")
    brightest = 0.0
    for job in jobs:
        inputs = job["inputs"]
        sky = max(inputs.sky.radiance) * (float(inputs.sky.map.max()) if inputs.sky.map is not None else 1.0)
        brightest = max(brightest, sum(max(sun.irradiance) for sun in inputs.suns) / math.pi + sky)
    if brightest <= clamp:
        return None
    return (f"The snow may be up to about {brightest:.3g} W/m²/sr bright, and Clamp Indirect ({clamp:g}) cuts the "
            "light it throws on nearby objects: raise it or set 0 (Render Properties > Light Paths > Clamping)")


def _light_warnings(scene, jobs, scattering):
    """What the user should know about the light once it is known (the world rendered); `scattering`: some
    baked snow is scattered by Cycles."""
    warnings = []
    if all(not job["inputs"].suns and not job["inputs"].lamps and max(job["inputs"].sky.radiance) <= 0.0
           for job in jobs):
        warnings.append("Nothing lights the snow (no lamp, black world): the bake is black")
    clamp = _clamp_warning(scene, jobs, scattering)
    if clamp:
        warnings.append(clamp)
    return warnings


def _summary(quality, inputs, seconds):
    suns, lamps = len(inputs.suns), len(inputs.lamps)
    parts = [quality.title(), f"{suns} sun{'s' if suns != 1 else ''}"]
    if lamps:
        parts.append(f"{lamps} lamp{'s' if lamps != 1 else ''}")
    parts += [f"sky {inputs.sky.description}",
             f"{len(inputs.occluders)} occluder parts", f"{seconds:.1f} s"]
    return ", ".join(parts)


def _remove(path):
    try:
        os.remove(path)
    except FileNotFoundError:
        pass


def _remove_baked_grids(obj):
    """Takes the baked grids out of obj's file (the core rewrites it atomically; the other grids stay as they
    were). A file that is missing, packed or linked has nothing Firn can take out: the bake is just forgotten."""
    volume = obj.data
    path = bake_state.snow_path(obj)
    if obj.library or volume.library or volume.packed_file is not None or cache.file_problem(volume):
        return
    try:
        removed = firncore.remove_grids(path, [*materials.BAKED_GRIDS, materials.SCATTER_GRID])
    except (OSError, ValueError) as error:
        raise UserError(f"Cannot clear the bake of '{obj.name}' ({error}); it stays baked. "
                        f"{cache.WRITE_ADVICE}") from error
    if removed:
        cache.reload_grids(volume)


def keep_baked_optics(settings, baked_optics):
    """The optics a bake was made with (firncore.VolumeOptics): its material renders with them until the next."""
    settings.bake_extinction_per_density = baked_optics.extinction_per_density
    settings.bake_albedo = baked_optics.albedo
    settings.bake_anisotropy = baked_optics.g


def adopt_bake(obj, baked_optics, signature, summary, proxy_colours=None):
    """After the baked grids arrived in obj's file: reload them, remember what the bake was made from (the scene
    `signature` taken before baking, the optics, the file as it is now) and render the snow from the bake; its
    viewport proxy shows `proxy_colours` (sampled by the worker) or the file's."""
    volume = obj.data
    cache.reload_grids(volume)
    settings = obj.firn
    settings.is_snow = True  # any baked Volume is Firn snow from now on: its optics are in Snow Material
    keep_baked_optics(settings, baked_optics)
    settings.bake_summary = summary
    bake_state.store(obj, dict(signature, snow=bake_state.snow_digest(obj)))
    materials.ensure_snow_material(obj)
    proxy.show_bake(obj, proxy_colours)


class FIRN_OT_bake_scattering(FirnJobMixin, bpy.types.Operator):
    """Compute the light scattered inside the selected snow from the scene's Sun lamps, world and objects,
    and render the snow from it"""

    bl_idname = "firn.bake_scattering"
    bl_label = "Bake Scattering"
    bl_options = {"UNDO"}
    job_label = BAKE_LABEL
    job_passes_events = True

    quality: bpy.props.EnumProperty(name="Quality", items=BAKE_QUALITY_ITEMS, default="FINAL")
    seed: bpy.props.IntProperty(name="Seed", description="Same scene and seed, same bake", default=0, min=0)

    @classmethod
    def poll(cls, context):
        if not (object_mode_poll(cls, context) and no_job_poll(cls)):
            return False
        if not bake_targets(context):
            cls.poll_message_set("Select snow, or Volume objects with a 'density' grid")
            return False
        return True

    def prepare(self, context):
        if not hasattr(firncore, "bake"):
            raise UserError("This build of Firn's core cannot bake (firncore.bake is missing): update Firn")
        jobs, warnings = [], []
        for obj in bake_targets(context):
            path = check_volume(obj)
            volume_optics = volume_optics_of(obj)
            signature = bake_inputs.signature(context, obj)
            signature["optics"] = bake_state.optics_digest(obj)
            inputs = bake_inputs.gather(context, obj)
            warnings.extend(w for w in inputs.warnings if w not in warnings)
            jobs.append({"name": obj.name, "path": path, "staged": path + _STAGED_SUFFIX,
                         "stamp": bake_state.file_stamp(path), "optics": volume_optics, "inputs": inputs,
                         "signature": signature, "proxy_points": proxy.vertex_positions(obj)})
        unlit = [job["inputs"].frame for job in jobs if job["inputs"].sky is None]
        world = bake_inputs.world_request(context.scene, unlit) if unlit else None  # last: it writes a file
        return {"jobs": jobs, "warnings": warnings, "quality": self.quality, "seed": self.seed, "current": 0,
                "world": world}

    def job_status(self, inputs, progress):
        if inputs["world"] is not None:
            return inputs["world"].status
        jobs = inputs["jobs"]
        part = f"{jobs[inputs['current']]['name']} ({inputs['current'] + 1}/{len(jobs)}) " if len(jobs) > 1 else ""
        return part + progress.stage

    @staticmethod
    def compute(inputs, progress):
        """Worker thread: render the world (a child Blender), then bake every object into its staged copy; on any
        failure or cancel, delete them all."""
        seconds = []
        try:
            render_world(inputs, progress)
            for index, job in enumerate(inputs["jobs"]):
                inputs["current"] = index
                if progress.cancelled:
                    raise firncore.Cancelled("cancelled")
                started = time.perf_counter()
                _bake_job(job, inputs["quality"], inputs["seed"], progress)
                seconds.append(time.perf_counter() - started)
        except BaseException:
            for job in inputs["jobs"]:
                _remove(job["staged"])
            raise
        return seconds

    def apply(self, context, inputs, seconds):
        baked, changed_settings, scattering = [], [], False
        try:
            for job, duration in zip(inputs["jobs"], seconds):
                obj = bpy.data.objects.get(job["name"])
                if obj is None or obj.type != "VOLUME" or bake_state.snow_path(obj) != job["path"] \
                        or bake_state.file_stamp(job["path"]) != job["stamp"]:
                    self.report({"WARNING"}, f"'{job['name']}' or its volume changed during the bake: bake it again")
                    continue
                os.replace(job["staged"], job["path"])
                adopt_bake(obj, job["optics"], job["signature"], _summary(inputs["quality"], job["inputs"], duration),
                           job["proxy_colours"])
                changed_settings.extend(_render_settings(obj))
                scattering = scattering or materials.material_form(obj) == "BAKED_SCATTER"
                baked.append(obj.name)
        finally:
            for job in inputs["jobs"]:
                _remove(job["staged"])
        if scattering:
            changed_settings.extend(scatter_render_settings(context.scene))
        for warning in inputs["warnings"] + _light_warnings(context.scene, inputs["jobs"], scattering):
            self.report({"WARNING"}, warning)
        if changed_settings:
            self.report({"WARNING"}, "Changed for baked snow: " + "; ".join(changed_settings))
        if baked:
            total = sum(seconds)
            self.report({"INFO"}, f"Baked {', '.join(baked)} ({inputs['quality'].title()}) in {total:.1f} s")


class FIRN_OT_clear_bake(bpy.types.Operator):
    """Forget the bake of the selected snow: it renders from its optics again"""

    bl_idname = "firn.clear_bake"
    bl_label = "Clear Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not any(obj.firn.bake_fingerprint for obj in bake_targets(context)):
            cls.poll_message_set("Select baked snow")
            return False
        return no_job_poll(cls)  # it rewrites the snow's file, which a running job may read

    def execute(self, context):
        cleared = []
        for obj in bake_targets(context):
            if not obj.firn.bake_fingerprint:
                continue
            if obj.data.is_sequence:
                self.report({"ERROR"}, f"'{obj.name}' is lit frame by frame: {sequence_advice(obj)}")
                continue
            try:
                _remove_baked_grids(obj)
            except UserError as error:
                self.report({"ERROR"}, str(error))
                continue
            obj.firn.bake_fingerprint = ""
            obj.firn.bake_summary = ""
            materials.ensure_snow_material(obj)
            proxy.show_bake(obj)
            cleared.append(obj.name)
        if not cleared:
            return {"CANCELLED"}
        self.report({"INFO"}, f"Cleared the bake of {', '.join(cleared)}")
        return {"FINISHED"}


classes = (FIRN_OT_bake_scattering, FIRN_OT_clear_bake)
