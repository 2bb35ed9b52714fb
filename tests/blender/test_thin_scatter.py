"""Thin snow scattered by Cycles itself (material form BAKED_SCATTER, docs/vdb-contract.md "Thin snow"): where the
`firn_scatter` grid is 0 the material is the baked one, where it holds the density Cycles path-traces the snow,
which must then agree with the core's independent Monte Carlo (firncore.monte_carlo_radiance) of the same snow and
light. The grids are written here, so these tests need no core bake."""

import itertools

import bpy
import numpy as np
import pytest
from mathutils import Vector

from bake_helpers import (K, RHO, S, black_world, needs_core_bake, optics_with, ortho_camera, render, uniform_source,
                          uniform_world, volume_object, write_volume)
from firn.bake import inputs as bake_inputs, operators as bake, state as bake_state
from firn.common.core import firncore
from firn.material import nodes as materials

# Thin snow: sigma_t h = 1 on 1 cm voxels, two layers (optical depth 2), omega and g of every channel different.
THIN_K, THIN_RHO, VOXEL = 1.0, 100.0, 0.01  # m²/kg, kg/m³, m
ALBEDO, G = (0.95, 0.9, 0.8), 0.6
SUN_TOWARDS, SUN_IRRADIANCE, SKY = (0.866, 0.0, 0.5), 3.0, 0.1  # from 30° elevation; W/m²; W/m²/sr
LO, HI = (-12, -12, -1), (11, 11, 0)  # the slab's voxels (24 x 24 x 2)


def thin_slab(directory, share, k, rho, optics, source=S):
    """A slab with constant baked grids and a firn_scatter grid of `share` times its density as a bake writes it
    where the slab scatters (docs/vdb-contract.md): on voxels SCATTER_SCALE times the density's, those within
    SCATTER_SCALE density voxels of one of the slab's, each shifted by half its own voxel; taken up by the add-on's
    post-bake step. The file
    says it is in Cycles' convention (firn_half_voxel_shift), so the core reads the same snow as Cycles draws."""
    import pyopenvdb

    path = write_volume(f"{directory}/thin.vdb", VOXEL, LO, HI, rho, uniform_source(source))
    grids = list(pyopenvdb.readAll(path)[0])
    scale = firncore.SCATTER_SCALE
    coarse = pyopenvdb.createLinearTransform(voxelSize=scale * VOXEL)
    coarse.translate((-scale * VOXEL / 2,) * 3)  # coarse voxel J where density voxel scale J is
    scatter = pyopenvdb.FloatGrid()
    scatter.name, scatter.transform = materials.SCATTER_GRID, coarse
    accessor = scatter.getAccessor()
    # The coarse J with |v - scale J| <= scale for one of the slab's voxels v = lo … hi along each axis.
    hats = [range(-(-lo // scale) - 1, hi // scale + 2) for lo, hi in zip(LO, HI)]
    for J in itertools.product(*hats):
        accessor.setValueOn(J, share * rho)
    pyopenvdb.write(path, grids=grids + [scatter], metadata={"firn_half_voxel_shift": True})
    obj = volume_object(path, "Snow")
    bpy.context.view_layer.update()
    obj.firn.is_snow, obj.firn.optics_mode, obj.firn.extinction_per_density = True, "CUSTOM", k
    signature = dict(bake_inputs.signature(bpy.context, obj), optics=bake_state.optics_digest(obj))
    bake.adopt_bake(obj, optics, signature, "test grids")
    return obj


def test_share_zero_renders_as_the_bake_and_off_builds_the_baked_form(clean_scene, tmp_path):
    black_world()
    obj = thin_slab(str(tmp_path), 0.0, K, RHO, optics_with(K, ALBEDO, G))
    material = materials.snow_material(obj)
    assert materials.material_form(obj) == "BAKED_SCATTER" and materials.is_baked_material(material)
    nodes = material.node_tree.nodes
    assert nodes["Firn Scatter"].attribute_name == materials.SCATTER_GRID
    assert tuple(nodes["Firn Volume"].inputs["Color"].default_value)[:3] == pytest.approx(ALBEDO)
    assert nodes["Firn Volume"].inputs["Anisotropy"].default_value == pytest.approx(G)
    assert tuple(nodes["Firn Volume"].inputs["Absorption Color"].default_value)[:3] == (0.0, 0.0, 0.0)
    ortho_camera((0.0, 0.0, 0.0), (0.3, 0.2, 0.93), 0.06)
    mixed = render(str(tmp_path), size=(4, 4), samples=4, name="mixed")

    obj.firn.scatter_thin = False  # the option rebuilds the material, no re-bake
    assert materials.material_form(obj) == "BAKED"
    assert "Firn Scatter" not in material.node_tree.nodes and material.get("firn_form") == "BAKED"
    baked = render(str(tmp_path), size=(4, 4), samples=4, name="baked")
    assert baked.min() > 0.1 * min(S)  # the bake is drawn
    np.testing.assert_allclose(mixed, baked, rtol=1e-4)


def pixel_rays(camera, size):
    """Each pixel centre's ray of an orthographic camera: origins, directions (world, m), rows bottom up."""
    scale, width = camera.data.ortho_scale, size
    to_world = camera.matrix_world
    direction = (to_world.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
    origins = [to_world @ Vector((((i + 0.5) / width - 0.5) * scale, ((j + 0.5) / width - 0.5) * scale, 0.0))
               for j in range(width) for i in range(width)]
    return np.array(origins, float), np.tile(np.array(direction, float), (len(origins), 1))


def test_scattering_snow_is_the_monte_carlo_of_the_same_snow(clean_scene, tmp_path):
    """Every voxel scatters: the baked emission is off (its grids hold S, which would show) and Cycles renders the
    slab's light brute force, with the volume bounces the bake operator sets; the Monte Carlo runs on the same
    file. The middle of a wide slab is uniform sideways, so the pixels' spread gives Cycles' standard error."""
    uniform_world((SKY,) * 3)
    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy, sun_data.angle = SUN_IRRADIANCE, 0.0093
    sun = bpy.data.objects.new("Sun", sun_data)
    sun.rotation_euler = (-Vector(SUN_TOWARDS)).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(sun)
    optics = optics_with(THIN_K, ALBEDO, G)
    obj = thin_slab(str(tmp_path), 1.0, THIN_K, THIN_RHO, optics, source=(5.0, 5.0, 5.0))
    assert materials.material_form(obj) == "BAKED_SCATTER"
    scene = bpy.context.scene
    changed = bake.scatter_render_settings(scene)
    assert scene.cycles.volume_bounces >= 32 and scene.cycles.max_bounces >= 32 and len(changed) == 2
    assert "darkens" in bake._clamp_warning(scene, [], scattering=True)  # factory clamp 10
    scene.cycles.sample_clamp_direct = scene.cycles.sample_clamp_indirect = 0.0  # as the warning asks
    scene.render.film_transparent = True  # the reference leaves the sky seen straight through the snow out
    scene.cycles.seed = 0
    size = 6
    camera = ortho_camera((0.0, 0.0, -0.01), (-0.433, 0.25, 0.866), 0.06)  # 60° up, 150° round from the sun
    bpy.context.view_layer.update()
    image = render(str(tmp_path), size=(size, size), samples=256, name="scatter").reshape(-1, 3)

    origins, directions = pixel_rays(camera, size)
    mean, error = firncore.monte_carlo_radiance(
        bake_state.snow_path(obj), optics, origins, directions,
        suns=[firncore.SunLight(SUN_TOWARDS, (SUN_IRRADIANCE,) * 3, 0.0093)], sky=firncore.Sky((SKY,) * 3),
        occluders=[], samples=2048, seed=5)
    cycles_mean, reference = image.mean(axis=0), mean.mean(axis=0)
    standard_error = np.hypot(image.std(axis=0, ddof=1) / np.sqrt(len(image)),
                              np.sqrt((error ** 2).sum(axis=0)) / len(error))
    assert reference.min() > 0.05  # W/m²/sr: light scattered in the slab, not the baked S (5)
    assert np.all(np.abs(cycles_mean - reference) < 4.0 * standard_error), (cycles_mean, reference, standard_error)


@needs_core_bake
def test_a_bake_of_thin_snow_scatters_it_and_sets_the_bounces(clean_scene, tmp_path):
    """The core's bake marks a thin slab (sigma_t h = 1) for Cycles to scatter; the operator raises the scene's
    bounces; Clear Bake takes firn_scatter out with the other baked grids."""
    uniform_world((SKY,) * 3)
    path = write_volume(f"{tmp_path}/slab.vdb", VOXEL, (-8, -8, -2), (7, 7, 0), THIN_RHO)
    obj = volume_object(path, "Slab")
    obj.firn.optics_mode, obj.firn.extinction_per_density = "CUSTOM", THIN_K
    obj.firn.albedo, obj.firn.anisotropy = ALBEDO, G
    obj.select_set(True)
    scene = bpy.context.scene
    assert scene.cycles.volume_bounces < 32
    assert bpy.ops.firn.bake_scattering(quality="DRAFT") == {"FINISHED"}
    assert materials.SCATTER_GRID in firncore.grid_names(path)
    assert materials.material_form(obj) == "BAKED_SCATTER"
    assert (scene.cycles.volume_bounces, scene.cycles.max_bounces) == (32, 32)
    assert tuple(obj.firn.bake_albedo) == pytest.approx(ALBEDO) and obj.firn.bake_anisotropy == pytest.approx(G)
    assert bpy.ops.firn.clear_bake() == {"FINISHED"}
    assert materials.SCATTER_GRID not in firncore.grid_names(path)
