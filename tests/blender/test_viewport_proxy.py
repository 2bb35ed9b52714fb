"""The snow's viewport proxy (issue 17) in blender -b: made with the snow, rebuilt with it, where the volume is
drawn, never rendered, never holding or stopping snow or light, and shown as the Display setting says."""

import bpy
import numpy as np
import pytest

from firn.bake import inputs as bake_inputs
from firn.common.core import firncore
from firn.snow_layer import operators as snow_operators, proxy as snow_proxy
from scene_helpers import select_only


def add_plane(size=2.0, **kwargs):
    bpy.ops.mesh.primitive_plane_add(size=size, **kwargs)
    return bpy.context.object


def snow_on_plane(**settings):
    ground = add_plane()
    select_only(ground)
    assert bpy.ops.firn.add_snow_layer(depth=0.1, **settings) == {"FINISHED"}
    return ground, bpy.context.object


def world_metres(obj, metres=1.0):
    """The proxy's vertices in world metres, as the viewport draws them (matrix_world, Blender units × metres)."""
    mesh = obj.data
    local = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", local)
    matrix = np.array(obj.matrix_world, np.float64)
    return ((local.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]) * metres).astype(np.float32)


def test_proxy_exists_after_add_snow_layer(clean_scene):
    _ground, snow = snow_on_plane()
    proxy = snow_proxy.proxy_of(snow)
    assert proxy is not None and proxy.type == "MESH" and proxy.firn.is_proxy
    assert proxy.parent == snow and proxy.name == "Snow Proxy"
    assert 100 < len(proxy.data.polygons) <= snow_proxy.MAX_TRIANGLES
    assert not proxy.hide_viewport and proxy.hide_select
    assert snow.firn.display == "SURFACE" and snow.display_type == "BOUNDS"  # no 3-D texture in the viewport
    material = proxy.data.materials[0]
    colour = material.node_tree.nodes["Firn Preview BSDF"].inputs["Base Color"].default_value
    assert min(colour[:3]) > 0.8 and tuple(material.diffuse_color[:3]) == pytest.approx(colour[:3])  # white snow


def test_proxy_is_excluded_from_render(clean_scene):
    _ground, snow = snow_on_plane()
    proxy = snow_proxy.proxy_of(snow)
    assert proxy.hide_render  # final renders
    # Rendered viewport (Cycles renders what the viewport shows): no ray sees it.
    assert not any(getattr(proxy, f"visible_{ray}") for ray in
                   ("camera", "diffuse", "glossy", "transmission", "volume_scatter", "shadow"))
    assert not snow.hide_render  # the volume is what renders


@pytest.mark.parametrize("metres", [1.0, 0.01])
def test_proxy_lies_where_the_density_ends(clean_scene, metres):
    clean_scene.unit_settings.scale_length = metres
    ground = add_plane(size=2.0 / metres)
    select_only(ground)
    assert bpy.ops.firn.add_snow_layer(depth=0.1 / metres, spacing=0.05 / metres) == {"FINISHED"}
    snow = bpy.context.object
    bpy.context.view_layer.update()
    points = world_metres(snow_proxy.proxy_of(snow), metres)
    # The level set is the signed distance (m) to the snow surface: 0 on it (vdb-contract.md). The proxy lies
    # OUTSIDE_VOXELS outside it, where the density ends, to within a voxel.
    distance = firncore.sample_grid(bpy.path.abspath(snow.data.filepath), "surface", points)
    assert np.abs(distance - snow_proxy.OUTSIDE_VOXELS * snow.firn.voxel_size).max() <= snow.firn.voxel_size
    top = 0.1 + snow_proxy.OUTSIDE_VOXELS * snow.firn.voxel_size
    assert points[:, 2].max() == pytest.approx(top, abs=0.02)  # the top of 10 cm of snow, in metres


def _delete_as_a_user_does(obj):
    """The viewport's Delete (X): Blender keeps the children and drops the parent's transform from them."""
    select_only(obj)
    assert bpy.ops.object.delete() == {"FINISHED"}
    bpy.context.view_layer.update()


def test_the_proxy_and_surface_mesh_stay_where_they_are_drawn_when_the_snow_is_deleted(clean_scene):
    """Children in the snow's space kept an identity transform: with the snow deleted, a scene in centimetres drew
    them 100 times too small at the origin (review finding)."""
    metres = 0.01  # Unit Scale: the snow's transform is a scale of 100
    clean_scene.unit_settings.scale_length = metres
    select_only(add_plane(size=2.0 / metres))
    assert bpy.ops.firn.add_snow_layer(depth=0.1 / metres, spacing=0.05 / metres, surface_mesh=True) == {"FINISHED"}
    snow = bpy.context.object
    bpy.context.view_layer.update()
    children = [snow_proxy.proxy_of(snow), bpy.data.objects[f"{snow.name} Surface"]]
    drawn = [world_metres(child, metres) for child in children]
    _delete_as_a_user_does(snow)
    for child, before in zip(children, drawn):
        assert child.parent is None
        np.testing.assert_allclose(world_metres(child, metres), before, atol=1e-5)


def test_proxy_follows_regenerate_and_rebuild(clean_scene):
    _ground, snow = snow_on_plane()
    first = snow_proxy.proxy_of(snow)
    first_mesh = first.data.name
    snow.firn.layer.depth = 0.3
    assert bpy.ops.firn.regenerate_snow() == {"FINISHED"}
    proxies = [child for child in snow.children if child.firn.is_proxy]
    assert len(proxies) == 1
    assert world_metres(proxies[0])[:, 2].max() == pytest.approx(0.3, abs=0.04)
    assert first_mesh not in bpy.data.meshes or bpy.data.meshes[first_mesh] == proxies[0].data  # old mesh freed
    assert len([m for m in bpy.data.materials if m.name.startswith("Firn Preview")]) == 1  # reused

    holder = snow.firn.metaballs
    import bmesh

    edit = bmesh.new()
    edit.from_mesh(holder.data)
    bmesh.ops.delete(edit, geom=[v for v in edit.verts if v.co.x > 0.0], context="VERTS")
    edit.to_mesh(holder.data)
    edit.free()
    select_only(snow)
    assert bpy.ops.firn.rebuild_from_metaballs() == {"FINISHED"}
    points = world_metres(snow_proxy.proxy_of(snow))
    assert points[:, 0].max() < 0.3  # the right half's snow is gone from the proxy too


def test_proxy_holds_and_stops_no_snow_or_light(clean_scene):
    ground, snow = snow_on_plane()
    proxy = snow_proxy.proxy_of(snow)
    assert bake_inputs.occluder_objects(bpy.context.view_layer) == [ground]
    assert not snow_operators.is_snow_target(proxy)
    layer = snow.firn.layer
    assert proxy not in snow_operators._occluder_objects(bpy.context, layer, [ground])


def test_display_setting(clean_scene):
    _ground, snow = snow_on_plane()
    proxy = snow_proxy.proxy_of(snow)
    output = snow.active_material.node_tree.nodes["Firn Output"]
    assert output.target == "CYCLES"  # EEVEE (Material Preview) does not slice the volume over the proxy
    snow.firn.display = "VOLUME"
    assert proxy.hide_viewport and snow.display_type == "TEXTURED" and output.target == "ALL"
    snow.firn.display = "BOUNDS"
    assert proxy.hide_viewport and snow.display_type == "BOUNDS" and output.target == "CYCLES"
    snow.firn.display = "SURFACE"
    assert not proxy.hide_viewport and snow.display_type == "BOUNDS" and output.target == "CYCLES"
    # The choice survives a regenerate.
    snow.firn.display = "VOLUME"
    assert bpy.ops.firn.regenerate_snow() == {"FINISHED"}
    assert snow_proxy.proxy_of(snow).hide_viewport and snow.display_type == "TEXTURED"


def test_preview_material_follows_the_optics(clean_scene):
    _ground, snow = snow_on_plane()
    bsdf = snow_proxy.proxy_of(snow).data.materials[0].node_tree.nodes["Firn Preview BSDF"]
    before = tuple(bsdf.inputs["Base Color"].default_value)
    radius_before = tuple(bsdf.inputs["Subsurface Radius"].default_value)
    snow.firn.grain_radius = 1e-3  # old, coarse grains absorb more: a darker, more translucent snow
    after = tuple(bsdf.inputs["Base Color"].default_value)
    assert all(a < b for a, b in zip(after[:3], before[:3]))
    assert all(a > b for a, b in zip(bsdf.inputs["Subsurface Radius"].default_value, radius_before))


def test_proxy_shows_the_bake_until_it_is_cleared(clean_scene):
    from bake_helpers import uniform_world
    from firn.material import preview

    uniform_world((1.0, 1.0, 1.0))
    ground = add_plane(size=0.6)
    select_only(ground)
    assert bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.03) == {"FINISHED"}
    snow = bpy.context.object
    select_only(snow)
    assert bpy.ops.firn.bake_scattering(quality="DRAFT") == {"FINISHED"}
    proxy = snow_proxy.proxy_of(snow)
    mesh, material = proxy.data, proxy.data.materials[0]
    assert preview.is_showing_bake(material)
    assert snow.active_material.node_tree.nodes["Firn Output"].target == "CYCLES"  # the baked tree, for Cycles
    colours = np.empty(len(mesh.vertices) * 4, np.float32)
    mesh.attributes[preview.BAKED_ATTRIBUTE].data.foreach_get("color", colours)
    points = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", points)
    # The proxy's vertices are in the grids' metres: its colours are firn_source + firn_source_peak there.
    path = bpy.path.abspath(snow.data.filepath)
    expected = sum(firncore.sample_color_grid(path, name, points.reshape(-1, 3))
                   for name in ("firn_source", "firn_source_peak"))
    assert np.allclose(colours.reshape(-1, 4)[:, :3], expected, rtol=1e-6, atol=1e-7)
    assert expected.mean() > 0.0  # a white sky lights the snow: its top glows
    assert bpy.ops.firn.clear_bake() == {"FINISHED"}
    assert not preview.is_showing_bake(material) and preview.BAKED_ATTRIBUTE not in mesh.attributes
