"""Shared pieces of the sample scenes: a fresh scene with Firn, sky and sun, camera, snow, render, timings.

Run inside Blender; the sample scripts put this folder on sys.path.
"""

import argparse
import math
import os
import sys
import time

import addon_utils
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))


class Stages:
    """Times named stages and prints them: the demo's report."""

    def __init__(self):
        self.rows = []

    def run(self, name, fn, *args, **kwargs):
        start = time.perf_counter()
        result = fn(*args, **kwargs)
        self.rows.append((name, time.perf_counter() - start))
        print(f"firn sample: {name:<22} {self.rows[-1][1]:7.2f} s", flush=True)
        return result

    def total(self):
        return sum(seconds for _, seconds in self.rows)


def parse_args(description, default_output, add_arguments=None):
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--output", default=default_output, help="PNG to render")
    parser.add_argument("--width", type=int, default=500)
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--no-save", action="store_true", help="do not save the .blend next to the script")
    parser.add_argument("--blend", help="save the .blend here instead of next to the script")
    if add_arguments:
        add_arguments(parser)  # the sample's own
    return parser.parse_args(argv)


def new_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon_utils.enable("firn", default_set=True)
    scene = bpy.context.scene
    # Baked snow is brighter than Cycles' default indirect clamp (10): no clamp, as the bake advises.
    scene.cycles.sample_clamp_indirect = 0.0
    return scene


def nishita_sky(scene, sun_elevation_deg, sun_rotation_deg, strength=0.3):
    """Blender's physical sky; a matching sun lamp is added by `sun`."""
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    nodes = world.node_tree.nodes
    sky = nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    sky.sun_disc = False  # the sun lamp gives the direct light
    sky.sun_elevation = math.radians(sun_elevation_deg)
    sky.sun_rotation = math.radians(sun_rotation_deg)
    background = nodes["Background"]
    background.inputs["Strength"].default_value = strength
    world.node_tree.links.new(sky.outputs["Color"], background.inputs["Color"])
    scene.world = world


def overcast_sky(scene, radiance=1.0):
    """A uniform sky of `radiance` (W/m²/sr per channel), as under an overcast sky (Chrisman's sky hemisphere)."""
    world = bpy.data.worlds.new("Overcast")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (radiance, radiance, radiance, 1.0)
    scene.world = world


def sun(elevation_deg, rotation_deg, irradiance=4.0):
    """A sun lamp (irradiance in W/m², Blender's Strength) from the same direction as the Nishita sky's sun."""
    # Blender's sun points along its local -Z; tilt it down from the zenith by (90 - elevation).
    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(90 - elevation_deg), 0.0,
                                                   math.radians(rotation_deg + 90)))
    lamp = bpy.context.object
    lamp.data.energy = irradiance
    lamp.data.angle = math.radians(0.53)
    return lamp


def camera(location, look_at, lens=50.0):
    from mathutils import Vector

    bpy.ops.object.camera_add(location=location)
    cam = bpy.context.object
    cam.data.lens = lens
    cam.rotation_euler = (Vector(look_at) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = cam
    return cam


def material(name, rgb, roughness=0.5, metallic=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    mat.node_tree.links.new(bsdf.outputs["BSDF"], nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    mat.diffuse_color = (*rgb, 1.0)
    return mat


def add_snow(targets, **settings):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in targets:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = targets[0]
    if bpy.ops.firn.add_snow_layer(**settings) != {"FINISHED"}:
        raise RuntimeError("Add Snow Layer failed")
    return bpy.context.object


def add_snow_bands(targets, **settings):
    """Add Snow Layer that may make levels of detail: every snow object it made (its bands), finest first. Set the
    scene's camera and resolution first: they size the voxels."""
    before = set(bpy.data.objects)
    add_snow(targets, **settings)
    made = (obj for obj in bpy.data.objects if obj not in before and obj.firn.is_snow)
    return sorted(made, key=lambda obj: obj.firn.lod_level)


def render(scene, output, width, samples, aspect=(16, 9), label=None, stamp_time=False):
    """Cycles render to a PNG; `label` is written on the picture (comparison panels say what they show), and
    with `stamp_time` the render's own time (Blender's stamp measures it)."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    scene.render.resolution_x = width
    scene.render.resolution_y = width * aspect[1] // aspect[0]
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.abspath(output)
    stamp_label(scene, label)
    scene.render.use_stamp_render_time = stamp_time and label is not None
    os.makedirs(os.path.dirname(scene.render.filepath), exist_ok=True)
    bpy.ops.render.render(write_still=True)


def render_peak_mb(scene, output, width, samples, aspect=(16, 9)):
    """`render`, returning Cycles' own peak memory (MB): the "Peak" of the status lines Blender prints, read from
    this process's standard output (in background mode render_stats handlers get no text); nan if none."""
    import ctypes
    import re
    import tempfile

    libc = ctypes.CDLL(None)
    with tempfile.TemporaryFile() as log:
        saved = os.dup(1)
        libc.fflush(None)
        os.dup2(log.fileno(), 1)
        try:
            render(scene, output, width, samples, aspect)
        finally:
            libc.fflush(None)
            os.dup2(saved, 1)
            os.close(saved)
        log.seek(0)
        peaks = re.findall(r"Peak:([0-9.]+)M", log.read().decode(errors="replace"))
    return max(float(peak) for peak in peaks) if peaks else math.nan


def stamp_label(scene, label):
    """Blender's render stamp, burnt into the image, with the note `label` alone (no date, frame, etc.)."""
    r = scene.render
    r.use_stamp = label is not None
    if label is None:
        return
    for name in dir(r):
        if name.startswith("use_stamp_"):
            setattr(r, name, False)
    r.use_stamp_note, r.stamp_note_text = True, label
    r.stamp_font_size = max(12, r.resolution_x // 14)
    r.stamp_foreground, r.stamp_background = (1.0, 1.0, 1.0, 1.0), (0.0, 0.0, 0.0, 0.6)


def save_next_to(script_file, path=None):
    """Saves the scene to `path`, or next to the sample's script; its snow's cache folder goes beside it."""
    path = os.path.abspath(path) if path else os.path.splitext(os.path.abspath(script_file))[0] + ".blend"
    os.makedirs(os.path.dirname(path), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return path


def bake(snows, quality="FINAL"):
    """Bake Scattering on the given snow objects (synchronous in background mode)."""
    bpy.ops.object.select_all(action="DESELECT")
    for snow in snows:
        snow.select_set(True)
    bpy.context.view_layer.objects.active = snows[0]
    if bpy.ops.firn.bake_scattering(quality=quality) != {"FINISHED"}:
        raise RuntimeError("Bake Scattering failed")


def side_by_side(paths, output):
    """Joins PNGs of equal height left to right into one PNG (Blender's image API, no other dependency)."""
    import numpy as np

    images = [bpy.data.images.load(os.path.abspath(path)) for path in paths]
    height = images[0].size[1]
    parts = []
    for image in images:
        width, h = image.size
        if h != height:
            raise ValueError("side_by_side needs images of one height")
        pixels = np.empty(width * h * 4, np.float32)
        image.pixels.foreach_get(pixels)
        parts.append(pixels.reshape(h, width, 4))
    joined = np.concatenate(parts, axis=1)
    result = bpy.data.images.new("joined", joined.shape[1], height, alpha=True)
    result.pixels.foreach_set(joined.ravel())
    result.filepath_raw = os.path.abspath(output)
    result.file_format = "PNG"
    result.save()
    for image in images + [result]:
        bpy.data.images.remove(image)


def panels_sample(script_file, description, render_panels, add_arguments=None):
    """The whole job of a comparison sample: `render_panels(args, stages)` renders its panels and returns their
    PNGs, which are joined left to right into the output; then the .blend is saved."""
    name = os.path.splitext(os.path.basename(script_file))[0]
    args = parse_args(description, f"out/{name}.png", add_arguments)
    stages = Stages()
    side_by_side(render_panels(args, stages), args.output)
    if not args.no_save:
        stages.run("save .blend", save_next_to, script_file, args.blend)
    print(f"firn sample: total {stages.total():.2f} s -> {args.output}")


def snow_bake_render(script_file, description, build_scene, **snow_settings):
    """The whole job of a one-picture sample: build its scene, snow its targets, bake, render, save the .blend."""
    name = os.path.splitext(os.path.basename(script_file))[0]
    args = parse_args(description, f"out/{name}.png")
    stages = Stages()
    scene, targets = stages.run("build scene", build_scene)
    snow = stages.run("add snow layer", add_snow, targets, **snow_settings)
    stages.run("bake scattering", bake, [snow])
    print(f"firn sample: bake {snow.firn.bake_summary}")
    stages.run("render (Cycles)", render, scene, args.output, args.width, args.samples)
    if not args.no_save:
        stages.run("save .blend", save_next_to, script_file, args.blend)
    print(f"firn sample: total {stages.total():.2f} s -> {args.output}")
