"""Add Grain Snow in blender -b: the grain object Cycles renders as spheres, its ice, the light paths it needs,
and its errors."""

import math

import bpy
import numpy as np
import pytest

from bake_helpers import ortho_camera, render, uniform_world
from firn.grains import light_paths
from scene_helpers import select_only


def add_plane(size, **kwargs):
    bpy.ops.mesh.primitive_plane_add(size=size, **kwargs)
    return bpy.context.object


def grain_points(obj):
    """(centres (N, 3) world, radii (N,)) of the spheres the object evaluates to: instanced icospheres for the
    render (and in blender -b), points in an interactive viewport."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    centres, radii = [], []
    for instance in depsgraph.object_instances:
        if not (instance.is_instance and instance.parent and instance.parent.original == obj):
            continue
        if instance.object.type == "POINTCLOUD":
            cloud = instance.object.data
            n = len(cloud.points)
            local, r = np.empty(n * 3, np.float32), np.empty(n, np.float32)
            cloud.attributes["position"].data.foreach_get("vector", local)
            cloud.attributes["radius"].data.foreach_get("value", r)
            matrix = np.array(instance.matrix_world)
            return local.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3], r
        matrix = np.array(instance.matrix_world)  # a unit sphere scaled by the grain's radius
        centres.append(matrix[:3, 3])
        radii.append(np.linalg.norm(matrix[:3, 0]))
    assert centres, f"{obj.name} evaluates to no grain"
    return np.array(centres), np.array(radii)


def add_grains(**settings):
    assert bpy.ops.firn.add_grain_snow(**settings) == {"FINISHED"}
    return bpy.context.object


def test_one_point_per_grain_with_its_radius_on_the_plane(clean_scene):
    select_only(add_plane(0.2))
    grains = add_grains(grain_radius=0.002, grain_radius_variation=0.001, grain_count=1500, seed=3)
    assert grains.name == "Grain Snow" and grains.firn.is_grains
    centres, radii = grain_points(grains)
    assert len(radii) == 1500
    assert radii.min() >= 0.001 - 1e-7 and radii.max() <= 0.003 + 1e-7 and radii.std() > 1e-4
    assert np.abs(centres[:, :2]).max() < 0.1 + 3 * 0.003  # over the plane (edge grains lean out on others)
    assert (centres[:, 2] - radii).min() > -1e-5  # none sinks into the plane


def test_same_seed_same_grains(clean_scene):
    select_only(add_plane(0.1))
    first = grain_points(add_grains(grain_radius=0.002, grain_count=300, seed=7))[0]
    select_only(bpy.data.objects["Plane"])
    again = grain_points(add_grains(grain_radius=0.002, grain_count=300, seed=7))[0]
    select_only(bpy.data.objects["Plane"])
    other = grain_points(add_grains(grain_radius=0.002, grain_count=300, seed=8))[0]
    assert np.array_equal(first, again) and not np.array_equal(first, other)


def test_ice_material_refracts_at_the_ice_index_and_absorbs_red_most(clean_scene):
    select_only(add_plane(0.1))
    grains = add_grains(grain_radius=0.002, grain_count=50, ior=1.31)
    nodes = grains.active_material.node_tree.nodes
    assert nodes["Fresnel"].inputs["IOR"].default_value == pytest.approx(1.31)
    refraction = nodes["Refraction BSDF"]
    assert refraction.inputs["IOR"].default_value == pytest.approx(1.31)
    red, green, blue, _alpha = refraction.inputs["Color"].default_value
    assert blue > green > red and 0.99 < red < 1.0  # ice is blue; one grain of 2 mm absorbs little


def test_light_paths_raised_and_said_never_lowered(clean_scene):
    cycles = clean_scene.cycles
    cycles.transmission_bounces = 1024
    cycles.caustics_refractive = False
    changes = light_paths.raise_light_paths(clean_scene)
    assert changes == ["Total bounces 12 → 1024", "Glossy bounces 4 → 1024", "Refractive Caustics on"]
    assert cycles.max_bounces == cycles.glossy_bounces == 1024 and cycles.caustics_refractive
    assert light_paths.raise_light_paths(clean_scene) == []
    select_only(add_plane(0.1))
    cycles.glossy_bounces = 8
    add_grains(grain_radius=0.002, grain_count=50)
    assert cycles.glossy_bounces == 1024


def test_bad_input_is_refused_with_the_reason(clean_scene):
    bpy.ops.object.select_all(action="DESELECT")
    with pytest.raises(RuntimeError, match="Select the objects the grains fall on"):
        bpy.ops.firn.add_grain_snow()
    select_only(add_plane(0.1))
    with pytest.raises(RuntimeError, match="must be less than the Grain Radius"):
        bpy.ops.firn.add_grain_snow(grain_radius=0.001, grain_radius_variation=0.001)
    steep = add_plane(0.1, location=(1, 0, 0), rotation=(math.radians(75), 0, 0))
    select_only(steep)
    with pytest.raises(RuntimeError, match="No grain landed"):
        bpy.ops.firn.add_grain_snow(grain_count=100, max_slope=math.radians(60))
    assert "Grain Snow" not in bpy.data.objects


def _red_ground_under_grains(count, tmp_path, name):
    """Mean (R, G, B) seen from above of a red diffuse square under `count` grains of 2 mm, white sky."""
    ground = add_plane(0.06)
    red = bpy.data.materials.new("Red")
    red.diffuse_color = (0.8, 0.05, 0.05, 1.0)
    red.use_nodes = True
    red.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.05, 0.05, 1.0)
    ground.data.materials.append(red)
    select_only(ground)
    add_grains(grain_radius=0.002, grain_count=count, seed=1)
    uniform_world((1.0, 1.0, 1.0))
    ortho_camera((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), scale=0.04)
    image = render(str(tmp_path), size=(12, 12), samples=32, name=name)
    return image.reshape(-1, 3).mean(axis=0)


def test_red_ground_shows_through_thin_grain_snow_not_through_thick(clean_scene, tmp_path):
    """Chrisman's observation: colour bleeds through thin snow. One layer of grains lets the red ground show;
    ten layers hide most of it (more light is scattered back by the ice before it reaches the ground)."""
    thin = _red_ground_under_grains(250, tmp_path, "thin")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    import addon_utils

    addon_utils.enable("firn", default_set=True)
    thick = _red_ground_under_grains(2500, tmp_path, "thick")
    assert thin[0] / thin[1] > 2.0
    assert thick[0] / thick[1] < 0.7 * thin[0] / thin[1]
    assert thick[1] > thin[1]  # the ice scatters the sky back: thick grain snow is brighter in green


def test_multi_scale_grains_lie_on_the_snow_layer_which_takes_their_optics(clean_scene):
    """Grains over a volumetric layer (issue 12, item 5): they land on its surface, and the layer's optics become
    the grains' (Physical, their radius)."""
    ground = add_plane(0.2)
    select_only(ground)
    assert bpy.ops.firn.add_snow_layer(depth=0.03) == {"FINISHED"}
    snow = bpy.context.object
    snow.firn.optics_mode = "CUSTOM"
    select_only(snow)
    grains = add_grains(grain_radius=0.0015, grain_count=400, seed=2)
    centres, radii = grain_points(grains)
    assert np.median(centres[:, 2] - radii) > 0.02  # on the 3 cm of snow, not on the ground under it
    assert snow.firn.optics_mode == "PHYSICAL" and snow.firn.grain_radius == pytest.approx(0.0015)
