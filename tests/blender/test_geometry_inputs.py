"""Geometry as users' scenes have it (issue 11): any Unit Scale, open surfaces whose normals face down, modifiers
and instances as targets and occluders. Bad inputs are reported, never a traceback (docs/reliability.md)."""

import math

import bmesh
import bpy
import numpy as np
import pytest
from mathutils import Vector

from bake_helpers import mean_pixel, needs_core_bake, ortho_camera, render, uniform_world
from firn.bake import inputs as bake_inputs, state as bake_state
from firn.common import scene_geometry
from firn.common.core import firncore
from scene_helpers import density_at, select_only


def add_plane(size, **kwargs):
    bpy.ops.mesh.primitive_plane_add(size=size, **kwargs)
    return bpy.context.object


def add_snow(*targets, **settings):
    select_only(*targets)
    assert bpy.ops.firn.add_snow_layer(**settings) == {"FINISHED"}
    return bpy.context.object


def snow_top(snow, x, y):
    """Height (m) of the highest snow above (x, y) m, sampled every 2 mm."""
    column = [(x, y, z) for z in np.arange(0.0, 0.3, 0.002)]
    return max(z for (_, _, z), rho in zip(column, density_at(snow, *column)) if rho > 0.0)


def flip_faces(obj):
    mesh = bmesh.new()
    mesh.from_mesh(obj.data)
    bmesh.ops.reverse_faces(mesh, faces=mesh.faces)
    mesh.to_mesh(obj.data)
    mesh.free()


def collection_instance(name, location, *objects):
    """An Empty instancing a new collection (not linked to the scene) that holds `objects`, moved out of it."""
    collection = bpy.data.collections.new(name)
    for obj in objects:
        for owner in list(obj.users_collection):
            owner.objects.unlink(obj)
        collection.objects.link(obj)
    empty = bpy.data.objects.new(f"{name} Instance", None)
    empty.instance_type = "COLLECTION"
    empty.instance_collection = collection
    empty.location = location
    bpy.context.scene.collection.objects.link(empty)
    bpy.context.view_layer.update()
    return empty


# --- Unit Scale ------------------------------------------------------------------------------------------------

# The ground's height (m), off the voxel lattice: a ground on voxel centres (z = 0) puts a whole layer of voxels on
# the edge of "interior" (mean_density), where the last bit of a float decides, and flips it by 2 %.
GROUND_Z = 0.0137


def world_box(obj):
    """(2, 3) lowest and highest corner of the object's bounding box in world space (Blender units)."""
    corners = np.array([tuple(obj.matrix_world @ Vector(c)) for c in obj.bound_box])
    return np.array([corners.min(axis=0), corners.max(axis=0)])


def snow_in_a_scene_of_unit_scale(scene, metres_per_unit):
    """Snow on a 2 m ground, 0.1 m deep, at 0.05 m spacing: the same physical scene in any Unit Scale."""
    scene.unit_settings.scale_length = metres_per_unit
    unit = 1.0 / metres_per_unit  # Blender units per metre
    ground = add_plane(2.0 * unit, location=(0.0, 0.0, GROUND_Z * unit))
    snow = add_snow(ground, depth=0.1 * unit, spacing=0.05 * unit, seed=1)
    bpy.context.view_layer.update()
    return ground, snow


@pytest.mark.parametrize("metres_per_unit", [0.01, 100.0])
def test_same_physical_scene_same_snow_in_metres_at_any_unit_scale(clean_scene, metres_per_unit):
    _ground, reference = snow_in_a_scene_of_unit_scale(clean_scene, 1.0)
    expected = firncore.grid_statistics(bpy.path.abspath(reference.data.filepath), "density")
    expected_top, expected_density = snow_top(reference, 0.1, 0.2), reference.firn.mean_density
    expected_voxel, expected_box = reference.firn.voxel_size, world_box(reference)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)

    ground, snow = snow_in_a_scene_of_unit_scale(clean_scene, metres_per_unit)
    stats = firncore.grid_statistics(bpy.path.abspath(snow.data.filepath), "density")
    assert stats["active_voxels"] == pytest.approx(expected["active_voxels"], rel=0.03)
    assert snow.firn.mean_density == pytest.approx(expected_density, rel=0.01)
    assert snow.firn.voxel_size == pytest.approx(expected_voxel, rel=1e-6)  # m, whatever the scale
    assert snow_top(snow, 0.1, 0.2) == pytest.approx(expected_top, abs=0.004)  # 2 mm sampling, both sides
    assert expected_top - GROUND_Z == pytest.approx(0.1, abs=0.02)  # the depth asked for, in metres
    # The Volume scales its metres to Blender units, so it lies on the ground in the viewport.
    unit = 1.0 / metres_per_unit
    assert np.allclose(np.array(snow.matrix_world), np.diag([unit, unit, unit, 1.0]))
    # In the viewport (Blender units) the snow's box is the reference's box (at Unit Scale 1: metres) × units per
    # metre, around the ground.
    box, ground_box = world_box(snow), world_box(ground)
    assert box == pytest.approx(expected_box * unit, abs=expected_voxel * unit)
    assert np.all(box[0, :2] < ground_box[0, :2]) and np.all(box[1, :2] > ground_box[1, :2])


def test_lengths_are_typed_in_the_scene_units(clean_scene):
    """A centimetre scene: depth 10 (Blender units, shown as 10 cm) is 0.1 m of snow."""
    clean_scene.unit_settings.scale_length = 0.01
    ground = add_plane(200.0)
    snow = add_snow(ground, depth=10.0, spacing=5.0)
    assert snow.firn.layer.depth == pytest.approx(10.0)
    assert snow_top(snow, 0.1, 0.2) == pytest.approx(0.1, abs=0.02)


@pytest.mark.parametrize("metres_per_unit", [0.01, 100.0])
def test_default_lengths_are_metres_at_any_unit_scale(clean_scene, metres_per_unit):
    """Left at their defaults, depth and spacing are 10 cm and 5 cm (not 1 mm or 10 m) and show so."""
    clean_scene.unit_settings.scale_length = metres_per_unit
    snow = add_snow(add_plane(2.0 / metres_per_unit))
    assert snow.firn.layer.depth * metres_per_unit == pytest.approx(0.1)
    assert snow.firn.layer.spacing * metres_per_unit == pytest.approx(0.05)
    assert snow_top(snow, 0.1, 0.2) == pytest.approx(0.1, abs=0.02)


def test_rebuild_from_metaballs_keeps_metres(clean_scene):
    _ground, snow = snow_in_a_scene_of_unit_scale(clean_scene, 0.01)
    before = firncore.grid_statistics(bpy.path.abspath(snow.data.filepath), "density")["active_voxels"]
    assert bpy.ops.firn.rebuild_from_metaballs() == {"FINISHED"}
    after = firncore.grid_statistics(bpy.path.abspath(snow.data.filepath), "density")["active_voxels"]
    assert after == before  # same balls, same voxels: the point mesh was read back in metres


def test_depth_beyond_the_core_limit_is_reported_in_metres(clean_scene):
    clean_scene.unit_settings.scale_length = 100.0
    ground = add_plane(0.02)
    select_only(ground)
    with pytest.raises(RuntimeError, match="depth must be between 0 and 20 m"):
        bpy.ops.firn.add_snow_layer(depth=1.0, spacing=0.01)  # 1 unit = 100 m of snow


def bake_snow_at_unit_scale(scene, metres_per_unit, directory):
    """A 1 m ground with 5 cm of snow, a sun 40 degrees from the zenith and a blue sky, baked (Draft, seed 3);
    returns the radiance Cycles renders straight down on the snow's centre (W/m^2/sr)."""
    scene.unit_settings.scale_length = metres_per_unit
    unit = 1.0 / metres_per_unit
    uniform_world((0.5, 0.6, 0.8))
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy, sun.data.angle = 2.0, 0.0
    sun.rotation_euler = (math.radians(40), 0.0, 0.0)
    scene.collection.objects.link(sun)
    snow = add_snow(add_plane(1.0 * unit), depth=0.05 * unit, spacing=0.05 * unit, seed=2)
    assert bpy.ops.firn.bake_scattering(quality="DRAFT", seed=3) == {"FINISHED"}
    assert snow.firn.bake_state == "BAKED"
    ortho_camera((0, 0, 0), (0, 0, 1), scale=0.2 * unit, distance=0.5 * unit, clip_start=0.001 * unit)
    return mean_pixel(render(directory, size=(8, 8), name=f"unit_{metres_per_unit:g}"))


def test_bake_occluders_are_in_metres_in_a_centimetre_scene(clean_scene):
    clean_scene.unit_settings.scale_length = 0.01
    snow = add_snow(add_plane(200.0), depth=10.0, spacing=5.0)
    bpy.ops.mesh.primitive_cube_add(size=50.0, location=(100.0, 0.0, 100.0))  # 0.5 m at (1, 0, 1) m
    bpy.context.view_layer.update()
    frame = bake_inputs.Frame(snow, 0.01)
    assert frame.is_identity  # the snow's frame is world metres
    occluders = bake_inputs.gather_occluders(bake_inputs.occluder_objects(bpy.context.view_layer),
                                             bpy.context.evaluated_depsgraph_get(), frame)
    (cube,) = [o for o in occluders if o.name == "Cube"]
    assert cube.vertices.mean(axis=0) == pytest.approx((1.0, 0.0, 1.0), abs=1e-5)
    assert np.ptp(cube.vertices, axis=0) == pytest.approx((0.5, 0.5, 0.5), abs=1e-5)


@needs_core_bake
def test_bake_of_a_centimetre_scene_is_as_bright(clean_scene, tmp_path):
    """The volume's scale (100) turns Cycles' path lengths back into metres: σt (1/m) and the baked source render
    the same radiance as at Unit Scale 1."""
    reference = bake_snow_at_unit_scale(clean_scene, 1.0, str(tmp_path))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    import addon_utils

    addon_utils.enable("firn", default_set=True)
    scaled = bake_snow_at_unit_scale(bpy.context.scene, 0.01, str(tmp_path))
    assert reference.min() > 0.05
    assert scaled == pytest.approx(reference, rel=0.03)


# --- open surfaces and normals ---------------------------------------------------------------------------------

def test_flipped_plane_gets_snow_on_top_and_says_so(clean_scene, capfd):
    ground = add_plane(2.0)
    flip_faces(ground)
    snow = add_snow(ground, depth=0.1)
    assert "normals ignored on 1 open surface(s) facing down: snow falls on their upper side" in capfd.readouterr().out
    above, below = density_at(snow, (0, 0, 0.05), (0, 0, -0.05))
    assert above > 50.0 and below == 0.0


def test_closed_cube_gets_snow_on_top_only_and_keeps_its_normals(clean_scene, capfd):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0.5))
    snow = add_snow(bpy.context.object, depth=0.1)
    assert "normals ignored" not in capfd.readouterr().out
    on_top, inside, under = density_at(snow, (0, 0, 1.05), (0, 0, 0.5), (0, 0, 0.05))
    assert on_top > 50.0 and inside == 0.0 and under == 0.0


def test_closed_cube_with_inward_normals_is_reported(clean_scene):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0.5))
    cube = bpy.context.object
    flip_faces(cube)
    select_only(cube)
    with pytest.raises(RuntimeError, match="Recalculate Outside"):
        bpy.ops.firn.add_snow_layer(depth=0.1)
    assert not any(obj.firn.is_snow for obj in bpy.data.objects)


# --- modifiers and instances ----------------------------------------------------------------------------------

def test_modifiers_are_applied_to_targets(clean_scene):
    ground = add_plane(2.0)
    ground.modifiers.new("Array", "ARRAY").relative_offset_displace = (1.5, 0.0, 0.0)  # a second plane at x = 3 m
    snow = add_snow(ground, depth=0.1)
    first, second, gap = density_at(snow, (0, 0, 0.05), (3.0, 0, 0.05), (1.5, 0, 0.05))
    assert first > 50.0 and second > 50.0 and gap == 0.0


def test_shape_keys_and_edit_mode_edits_shape_the_targets(clean_scene):
    # A mesh without modifiers is read in place, not copied (scene_geometry._readable_in_place): its shape keys
    # must still apply, and in Edit Mode its unsaved edits must show, as to_mesh() gives them.
    ground = add_plane(2.0)
    ground.shape_key_add(name="Basis")
    raised = ground.shape_key_add(name="Raised")
    for point in raised.data:
        point.co.z += 0.5
    raised.value = 1.0
    bpy.context.view_layer.update()
    vertices, _triangles = scene_geometry.world_triangles([ground], bpy.context.evaluated_depsgraph_get())
    assert np.allclose(vertices[:, 2], 0.5)
    raised.value = 0.0
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.transform.translate(value=(0.0, 0.0, 0.25))
    bpy.context.view_layer.update()
    vertices, _triangles = scene_geometry.world_triangles([ground], bpy.context.evaluated_depsgraph_get())
    bpy.ops.object.mode_set(mode="OBJECT")
    assert np.allclose(vertices[:, 2], 0.25)


def test_triangle_corners_read_in_place_are_blenders_own(clean_scene):
    # The corners are read from Blender's MLoopTri and MLoop arrays in place (scene_geometry._loop_triangle_corners):
    # they must be the loop triangles' `vertices` as Blender gives them, for n-gons and for a modifier's to_mesh().
    bpy.ops.mesh.primitive_cylinder_add(vertices=7)  # 7-gon caps
    bpy.ops.mesh.primitive_monkey_add(location=(3.0, 0.0, 0.0))
    bpy.context.object.modifiers.new("Subdivision", "SUBSURF")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in bpy.context.scene.objects:
        evaluated = obj.evaluated_get(depsgraph)
        for mesh in (evaluated.data, evaluated.to_mesh()):
            mesh.calc_loop_triangles()
            expected = np.empty(len(mesh.loop_triangles) * 3, np.int32)
            mesh.loop_triangles.foreach_get("vertices", expected)
            assert scene_geometry._struct_array(mesh.loop_triangles, 4) is not None  # the in-place path is taken
            assert np.array_equal(scene_geometry._loop_triangle_corners(mesh), expected)
        evaluated.to_mesh_clear()


def test_collection_instance_shelters_the_ground(clean_scene):
    ground = add_plane(4.0)
    bpy.ops.mesh.primitive_cube_add(size=1.0, scale=(1.0, 1.0, 0.05))
    collection_instance("Table", (0, 0, 0.8), bpy.context.object)
    snow = add_snow(ground, depth=0.1)
    under, beside = density_at(snow, (0, 0, 0.04), (1.6, 0, 0.04))
    assert under == 0.0 and beside > 50.0


def test_collection_instance_as_target_gets_snow(clean_scene):
    empty = collection_instance("Ground", (3, 0, 0), add_plane(2.0))
    snow = add_snow(empty, depth=0.1)
    at_instance, at_original = density_at(snow, (3, 0, 0.05), (0, 0, 0.05))
    assert at_instance > 50.0 and at_original == 0.0
    assert [item.object for item in snow.firn.targets] == [empty]


def instance_on_points(points):
    """A point cloud object whose Geometry Nodes put a 1 m grid on each point."""
    mesh = bpy.data.meshes.new("Points")
    mesh.from_pydata(points, [], [])
    obj = bpy.data.objects.new("Points", mesh)
    bpy.context.scene.collection.objects.link(obj)
    tree = bpy.data.node_groups.new("Scatter", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    group_in, group_out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    grid = tree.nodes.new("GeometryNodeMeshGrid")
    grid.inputs["Size X"].default_value = grid.inputs["Size Y"].default_value = 1.0
    scatter = tree.nodes.new("GeometryNodeInstanceOnPoints")
    tree.links.new(group_in.outputs[0], scatter.inputs["Points"])
    tree.links.new(grid.outputs["Mesh"], scatter.inputs["Instance"])
    tree.links.new(scatter.outputs["Instances"], group_out.inputs[0])
    obj.modifiers.new("Scatter", "NODES").node_group = tree
    bpy.context.view_layer.update()
    return obj


def test_geometry_nodes_instances_all_get_snow(clean_scene):
    points = [(0, 0, 0), (3, 0, 0), (0, 3, 1)]
    snow = add_snow(instance_on_points(points), depth=0.1)
    values = density_at(snow, *[(x, y, z + 0.05) for x, y, z in points], (1.5, 0, 0.05))
    assert all(value > 50.0 for value in values[:3]) and values[3] == 0.0


def test_particle_instances_are_targets(clean_scene):
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0, 0, -5))
    tile = bpy.context.object
    emitter = add_plane(4.0, location=(0, 0, 0))
    emitter.modifiers.new("Tiles", "PARTICLE_SYSTEM")
    settings = emitter.particle_systems[0].settings
    settings.type, settings.count = "HAIR", 4
    settings.render_type, settings.instance_object, settings.particle_size = "OBJECT", tile, 1.0
    emitter.show_instancer_for_viewport = False  # only the tiles
    bpy.context.view_layer.update()
    parts = scene_geometry.evaluated_parts([emitter], bpy.context.evaluated_depsgraph_get())
    assert len(parts) == 4 and all(name.startswith("Plane.001 > Plane") for name, *_ in parts)


def test_instanced_occluder_is_gathered_for_the_bake(clean_scene):
    ground = add_plane(2.0)
    bpy.ops.mesh.primitive_cube_add(size=0.5)
    empty = collection_instance("Box", (0, 0, 1.0), bpy.context.object)
    objects = bake_inputs.occluder_objects(bpy.context.view_layer)
    assert set(objects) == {ground, empty}
    frame = bake_inputs.Frame(ground)  # identity
    occluders = bake_inputs.gather_occluders(objects, bpy.context.evaluated_depsgraph_get(), frame)
    (box,) = [o for o in occluders if o.name == "Box Instance > Cube"]
    assert len(box.triangles) == 12
    assert box.vertices.mean(axis=0) == pytest.approx((0, 0, 1.0), abs=1e-5)


@needs_core_bake
def test_instanced_occluder_casts_a_shadow_in_the_bake(clean_scene):
    uniform_world((0.0, 0.0, 0.0))
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy, sun.data.angle = 3.0, 0.0  # straight down
    clean_scene.collection.objects.link(sun)
    snow = add_snow(add_plane(2.0), depth=0.05, spacing=0.05)
    bpy.ops.mesh.primitive_cube_add(size=0.6)
    collection_instance("Roof", (0.5, 0, 0.6), bpy.context.object)
    select_only(snow)
    assert bpy.ops.firn.bake_scattering(quality="DRAFT", seed=1) == {"FINISHED"}
    import pyopenvdb

    grid = pyopenvdb.read(bake_state.snow_path(snow), "firn_source")
    accessor = grid.getConstAccessor()
    shade, sunlit = (max(accessor.getValue(grid.transform.worldToIndexCellCentered(p))) for p in
                     ((0.5, 0.0, 0.03), (-0.5, 0.0, 0.03)))
    # The sun straight down: the roof's footprint is dark but for the light the lit snow round it sends back off the
    # roof's underside (albedo 0.8, 0.3 m up, 0.6 m wide): the footprint's centre sees the underside with a view
    # factor ~0.55 and the underside the lit snow with ~0.45, so ~0.8 x 0.45 x 0.55 = 0.2 of the lit snow's light
    # (main read 0.198, then 0.211 with the sky traced on a lattice); without the shadow it would read 1.
    assert sunlit > 0.0 and shade < 0.35 * sunlit
