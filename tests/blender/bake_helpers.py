"""Shared by the bake tests: volumes written voxel by voxel with pyopenvdb, small Cycles renders read back from
32-bit EXR, and a marker for the tests that need the core's bake (firncore.bake, core branch 'bake')."""

import os

import bpy
import numpy as np
import pytest

from firn.bake import inputs as bake_inputs, operators as bake, state as bake_state
from firn.material import nodes as materials
from firn.common.core import firncore

needs_core_bake = pytest.mark.skipif(
    not hasattr(firncore, "bake"), reason="needs firncore.bake (the core's Bake Scattering, branch 'bake')")

K = 10.0  # m^2/kg
RHO = 300.0  # kg/m^3: sigma_t = 3000 /m, real snow's range (snow-optics.md); 1 cm voxels are 30 optical depths
S = (0.3, 0.5, 0.7)  # W/m^2/sr per unit extinction
S_X, S_Y, S_Z = (0.2, 0.1, 0.0), (0.05, 0.1, 0.15), (0.1, 0.2, 0.05)


def baked_slab(directory, source, voxel=0.01, half=20, depth=5, z_top=0, name="Snow", **placement):
    """A uniform slab (top voxels at z index `z_top`) with constant baked grids, taken up by the add-on's own
    post-bake step (bake.adopt_bake) as if the core had just written them."""
    lo, hi = (-half, -half, z_top - depth + 1), (half - 1, half - 1, z_top)
    path = write_volume(f"{directory}/{name}.vdb", voxel, lo, hi, RHO, source)
    obj = volume_object(path, name, **placement)
    bpy.context.view_layer.update()
    obj.firn.is_snow = True
    obj.firn.optics_mode = "CUSTOM"
    obj.firn.extinction_per_density = K
    signature = dict(bake_inputs.signature(bpy.context, obj), optics=bake_state.optics_digest(obj))
    bake.adopt_bake(obj, optics_with(K), signature, "test grids")
    return obj


def optics_with(extinction_per_density, albedo=(0.999, 0.998, 0.99), g=0.85):
    """The optics a test's grids are baked with (firncore.VolumeOptics)."""
    return firncore.VolumeOptics(extinction_per_density, albedo, g)


def write_volume(path, voxel, lo, hi, density, source=None):
    """A box of voxels with indices lo..hi (inclusive, per axis) holding `density` (kg/m^3), in Firn's convention
    (voxel i centred at i × voxel in Cycles: translation -voxel/2). `source`: {grid name: RGB} written as
    constant Vec3 grids over the same voxels (docs/vdb-contract.md). Voxel by voxel: Cycles renders tiles as
    empty."""
    import pyopenvdb

    def transform():
        t = pyopenvdb.createLinearTransform(voxelSize=voxel)
        t.translate((-voxel / 2,) * 3)
        return t

    grids = []
    values = {"density": density, **(source or {})}
    for name, value in values.items():
        grid = pyopenvdb.FloatGrid() if name == "density" else pyopenvdb.Vec3SGrid()
        grid.name = name
        grid.transform = transform()
        accessor = grid.getAccessor()
        for i in range(lo[0], hi[0] + 1):
            for j in range(lo[1], hi[1] + 1):
                for k in range(lo[2], hi[2] + 1):
                    accessor.setValueOn((i, j, k), value)
        grids.append(grid)
    pyopenvdb.write(path, grids=grids)
    return path


def add_contract_grids(path, source):
    """Adds constant baked grids over the density's active voxels of an existing file (what a bake writes)."""
    import pyopenvdb

    grids = list(pyopenvdb.readAll(path)[0])
    density = next(grid for grid in grids if grid.name == "density")
    for name, value in source.items():
        grid = pyopenvdb.Vec3SGrid()
        grid.name = name
        grid.transform = density.transform
        accessor = grid.getAccessor()
        for item in density.citerOnValues():
            if item["count"] != 1:
                raise AssertionError("density has tiles")
            accessor.setValueOn(item["min"], value)
        grids.append(grid)
    pyopenvdb.write(path, grids=grids)


def volume_object(path, name="Snow", location=(0, 0, 0), rotation=(0, 0, 0)):
    volume = bpy.data.volumes.new(name)
    volume.filepath = path
    volume.render.precision = "FULL"
    volume.render.clipping = 0.0
    obj = bpy.data.objects.new(name, volume)
    obj.location, obj.rotation_euler = location, rotation
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


def uniform_source(s, s_x=(0, 0, 0), s_y=(0, 0, 0), s_z=(0, 0, 0), peak=(0, 0, 0), peak_l1=(0, 0, 0)):
    return dict(zip(materials.BAKED_GRIDS, (s, s_x, s_y, s_z, peak, peak_l1)))


def black_world():
    world = bpy.data.worlds.new("Black")
    world.use_nodes = False
    world.color = (0.0, 0.0, 0.0)
    bpy.context.scene.world = world
    return world


def uniform_world(rgb):
    world = bpy.data.worlds.new("Uniform")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*rgb, 1.0)
    background.inputs["Strength"].default_value = 1.0
    bpy.context.scene.world = world
    return world


def ortho_camera(target, towards_camera, scale, distance=2.0, clip_start=0.001):
    """An orthographic camera looking at `target` from the direction `towards_camera` (unit, world)."""
    from mathutils import Vector

    direction = Vector(towards_camera).normalized()
    data = bpy.data.cameras.new("Camera")
    data.type = "ORTHO"
    data.ortho_scale = scale
    data.clip_start = clip_start
    camera = bpy.data.objects.new("Camera", data)
    camera.location = Vector(target) + distance * direction
    camera.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera
    return camera


def render(directory, size=(16, 16), samples=16, name="render"):
    """(height, width, 3) linear radiance of the scene camera's view: Cycles CPU, no denoising (Debian's Blender
    has no OpenImageDenoise), box pixel filter."""
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.pixel_filter_type = "BOX"
    scene.render.filter_size = 1.0
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    path = os.path.join(directory, f"{name}.exr")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path, check_existing=False)
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[:, :, :3]


def mean_pixel(image):
    return image.reshape(-1, 3).mean(axis=0)
