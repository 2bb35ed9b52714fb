"""Bake state: NONE -> BAKED -> OUTDATED (lamps, world, objects, optics, snow) -> NONE after Clear Bake, the panel
that shows it, and cancelling before the core runs. The baked grids are written here (bake_helpers), so these
tests need no core bake."""

import os

import bpy
import pytest

from bake_helpers import (S, add_contract_grids, baked_slab, optics_with, uniform_source, uniform_world,
                          write_volume)
from firn.bake import inputs as bake_inputs, operators as bake, state as bake_state, ui as bake_ui
from firn.material import nodes as materials
from firn.common.core import firncore
from test_snow_material import RecordingLayout


def state(obj):
    return bake_state.changes(obj)


def add_sun(rotation=(0.3, 0.0, 0.0)):
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(sun)
    bpy.context.view_layer.update()
    return sun


def test_volume_without_bake_is_none(clean_scene, tmp_path):
    bpy.ops.mesh.primitive_plane_add()
    bpy.ops.firn.add_snow_layer(depth=0.1)
    snow = bpy.context.object
    assert snow.firn.bake_state == "NONE" and state(snow) == ("NONE", [])


def test_bake_then_every_kind_of_change(clean_scene, tmp_path):
    uniform_world((1.0, 1.0, 1.0))
    sun = add_sun()
    bpy.ops.mesh.primitive_cube_add(location=(3, 0, 0))
    cube = bpy.context.object
    obj = baked_slab(str(tmp_path), uniform_source(S))
    assert obj.firn.bake_state == "BAKED" and state(obj) == ("BAKED", [])

    def outdated_by(change, undo, label):
        change()
        bpy.context.view_layer.update()
        assert state(obj) == ("OUTDATED", [label]), label
        assert obj.firn.bake_state == "OUTDATED"
        undo()
        bpy.context.view_layer.update()
        assert state(obj) == ("BAKED", []), label

    outdated_by(lambda: setattr(sun, "rotation_euler", (0.5, 0.0, 0.0)),
                lambda: setattr(sun, "rotation_euler", (0.3, 0.0, 0.0)), "lamps")
    energy = sun.data.energy
    outdated_by(lambda: setattr(sun.data, "energy", 2 * energy), lambda: setattr(sun.data, "energy", energy), "lamps")
    background = bpy.context.scene.world.node_tree.nodes["Background"]
    outdated_by(lambda: setattr(background.inputs["Strength"], "default_value", 2.0),
                lambda: setattr(background.inputs["Strength"], "default_value", 1.0), "world")
    outdated_by(lambda: setattr(cube, "location", (3, 0, 1)), lambda: setattr(cube, "location", (3, 0, 0)),
                "object Cube")
    outdated_by(lambda: setattr(cube, "hide_render", True), lambda: setattr(cube, "hide_render", False),
                "object Cube")
    outdated_by(lambda: setattr(obj.firn, "anisotropy", 0.5),
                lambda: setattr(obj.firn, "anisotropy", 0.845), "optics")
    outdated_by(lambda: setattr(obj, "location", (0, 0, 1)), lambda: setattr(obj, "location", (0, 0, 0)), "snow")

    point = bpy.data.objects.new("Bulb", bpy.data.lights.new("Bulb", "POINT"))  # a lamp lights the bake too
    bpy.context.scene.collection.objects.link(point)
    assert state(obj) == ("OUTDATED", ["lamps"])
    bpy.data.objects.remove(point)
    assert state(obj) == ("BAKED", [])

    path = bake_state.snow_path(obj)
    stat = os.stat(path)
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))  # the file was rewritten
    assert state(obj) == ("OUTDATED", ["snow"])


def test_edits_that_keep_the_vertex_count_are_seen_and_name_the_object(clean_scene, tmp_path):
    """Moving one vertex of an occluder or of the ground, or a modifier setting, keeps every count: the evaluated
    shape's digest still sees it; undoing it gives the bake back."""
    bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0, 0, -0.2))
    ground = bpy.context.object
    ground.name = "Ground"
    bpy.ops.mesh.primitive_cube_add(location=(3, 0, 0))
    cube = bpy.context.object
    obj = baked_slab(str(tmp_path), uniform_source(S))

    def moved_and_back(mesh_object):
        vertex = mesh_object.data.vertices[0]
        before = vertex.co.copy()
        vertex.co.z += 0.01  # 1 cm
        mesh_object.data.update()
        bpy.context.view_layer.update()
        assert state(obj) == ("OUTDATED", [f"object {mesh_object.name}"])
        vertex.co = before
        mesh_object.data.update()
        bpy.context.view_layer.update()
        assert state(obj) == ("BAKED", [])

    moved_and_back(cube)
    moved_and_back(ground)

    name = obj.name
    bpy.ops.ed.undo_push(message="baked")
    cube.data.vertices[3].co.x += 0.5
    cube.data.update()
    bpy.ops.ed.undo_push(message="vertex moved")
    bpy.context.view_layer.update()
    assert state(obj) == ("OUTDATED", ["object Cube"])
    bpy.ops.ed.undo()  # Blender's own undo
    obj = bpy.data.objects[name]
    bpy.context.view_layer.update()
    assert state(obj) == ("BAKED", [])


def test_a_modifier_setting_that_keeps_counts_outdates_the_bake(clean_scene, tmp_path):
    bpy.ops.mesh.primitive_cube_add(location=(3, 0, 0))
    cube = bpy.context.object
    displace = cube.modifiers.new("Displace", "DISPLACE")
    displace.strength = 0.1
    obj = baked_slab(str(tmp_path), uniform_source(S))
    displace.strength = 0.2
    bpy.context.view_layer.update()
    assert state(obj) == ("OUTDATED", ["object Cube"])
    displace.strength = 0.1
    bpy.context.view_layer.update()
    assert state(obj) == ("BAKED", [])


def test_many_changed_objects_are_counted(clean_scene, tmp_path):
    obj = baked_slab(str(tmp_path), uniform_source(S))
    for i in range(5):
        bpy.ops.mesh.primitive_cube_add(location=(3 + 3 * i, 0, 0))
    bpy.context.view_layer.update()
    assert state(obj) == ("OUTDATED", ["object Cube", "object Cube.001", "object Cube.002", "2 more objects"])


def test_a_fingerprint_of_an_older_firn_says_objects(clean_scene, tmp_path):
    import json

    bpy.ops.mesh.primitive_cube_add(location=(3, 0, 0))
    obj = baked_slab(str(tmp_path), uniform_source(S))
    parts = json.loads(obj.firn.bake_fingerprint)
    parts["occluders"] = "0123456789abcdef"  # one digest for every object
    obj.firn.bake_fingerprint = json.dumps(parts)
    assert state(obj) == ("OUTDATED", ["objects"])


def test_several_changes_are_all_named(clean_scene, tmp_path):
    sun = add_sun()
    obj = baked_slab(str(tmp_path), uniform_source(S))
    sun.rotation_euler = (1.0, 0.0, 0.0)
    obj.firn.extinction_per_density = 3.0
    bpy.context.view_layer.update()
    assert state(obj) == ("OUTDATED", ["lamps", "optics"])


def test_regenerated_snow_is_outdated_and_renders_from_its_optics(clean_scene, tmp_path):
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.05)
    snow = bpy.context.object
    add_contract_grids(bake_state.snow_path(snow), uniform_source(S))
    signature = dict(bake.bake_inputs.signature(bpy.context, snow), optics=bake_state.optics_digest(snow))
    bake.adopt_bake(snow, optics_with(12.0), signature, "test grids")
    assert state(snow) == ("BAKED", []) and materials.is_baked_material(materials.snow_material(snow))
    assert materials.snow_material(snow).node_tree.nodes["Firn Extinction"].inputs[1].default_value == 12.0

    assert bpy.ops.firn.regenerate_snow() == {"FINISHED"}
    assert state(snow) == ("OUTDATED", ["snow"])
    material = materials.snow_material(snow)
    assert not materials.is_baked_material(material)  # the new file has no baked grids


def test_clear_bake(clean_scene, tmp_path):
    obj = baked_slab(str(tmp_path), uniform_source(S))
    obj.select_set(True)
    obj.firn.anisotropy = 0.7  # changed after the bake: the optics material shows it after clearing
    assert bpy.ops.firn.clear_bake.poll()
    assert bpy.ops.firn.clear_bake() == {"FINISHED"}
    assert obj.firn.bake_state == "NONE" and obj.firn.bake_fingerprint == ""
    material = materials.snow_material(obj)
    assert not materials.is_baked_material(material)
    assert material.node_tree.nodes["Firn Volume"].inputs["Anisotropy"].default_value == pytest.approx(0.7)
    assert not bpy.ops.firn.clear_bake.poll()


def test_bake_operator_polls_for_volumes(clean_scene, tmp_path):
    bpy.ops.mesh.primitive_plane_add()
    assert not bpy.ops.firn.bake_scattering.poll()
    obj = baked_slab(str(tmp_path), uniform_source(S))
    bpy.ops.object.select_all(action="DESELECT")
    bpy.context.view_layer.objects.active = obj  # the active volume counts even when not selected
    assert bpy.ops.firn.bake_scattering.poll()


def draw_log(obj):
    log = {"props": [], "labels": [], "operators": [], "menus": []}
    bake_ui.draw_bake(RecordingLayout(log), obj)
    return log


def test_panel_shows_quality_buttons_and_state(clean_scene, tmp_path):
    sun = add_sun()
    obj = baked_slab(str(tmp_path), uniform_source(S))
    log = draw_log(obj)
    assert {"bake_quality", "bake_seed"} <= set(log["props"])
    assert {"firn.bake_scattering", "firn.clear_bake"} <= set(log["operators"])
    assert "Baked" in log["labels"] and "test grids" in log["labels"]
    sun.rotation_euler = (1.0, 0.0, 0.0)
    bpy.context.view_layer.update()
    labels = draw_log(obj)["labels"]
    assert "Needs re-bake" in labels and "Changed: lamps" in labels
    for panel in (bpy.types.FIRN_PT_bake, bpy.types.FIRN_PT_sidebar_bake):
        assert panel.poll(type("Context", (), {"object": obj}))
        assert not panel.poll(type("Context", (), {"object": sun}))
    assert bpy.types.FIRN_PT_sidebar_bake.bl_parent_id == "FIRN_PT_sidebar"


def test_cancel_before_the_core_runs_changes_nothing(clean_scene, tmp_path):
    """A cancel that arrives between objects: no staged copy is left and the files are as they were."""
    path = write_volume(str(tmp_path / "v.vdb"), 0.01, (0, 0, 0), (3, 3, 3), 300.0)
    with open(path, "rb") as file:
        before = file.read()
    staged = path + ".firn-bake.vdb"
    progress = firncore.Progress()
    progress.cancel()
    inputs = {"jobs": [{"path": path, "staged": staged}], "quality": "FINAL", "seed": 0, "world": None}
    with pytest.raises(firncore.Cancelled):
        bake.FIRN_OT_bake_scattering.compute(inputs, progress)
    assert not os.path.exists(staged)
    with open(path, "rb") as file:
        assert file.read() == before


def test_clamp_indirect_that_would_cut_bounce_light_is_reported(clean_scene):
    from firn.bake.inputs import BakeInputs, Sky, Sun

    scene = bpy.context.scene
    bright = {"inputs": BakeInputs([Sun("Sun", (0, 0, 1), (1000.0, 1000.0, 900.0), 0.01)], Sky((1.0,) * 3), [], None)}
    dim = {"inputs": BakeInputs([Sun("Sun", (0, 0, 1), (3.0, 3.0, 3.0), 0.01)], Sky((0.5,) * 3), [], None)}
    scene.cycles.sample_clamp_indirect = 10.0  # Cycles' default
    assert "Clamp Indirect (10)" in bake._clamp_warning(scene, [dim, bright])
    assert bake._clamp_warning(scene, [dim]) is None  # 3 / pi + 0.5 < 10
    scene.cycles.sample_clamp_indirect = 0.0  # no clamping
    assert bake._clamp_warning(scene, [bright]) is None


def test_status_names_the_object_being_baked(clean_scene):
    status = bake.FIRN_OT_bake_scattering.job_status
    progress = firncore.Progress()
    jobs = [{"name": "Snow"}, {"name": "Roof"}]
    assert status(None, {"jobs": jobs, "current": 1, "world": None}, progress) == "Roof (2/2) "
    assert status(None, {"jobs": jobs[:1], "current": 0, "world": None}, progress) == ""
    rendered = bake_inputs.RenderedWorld(request=None)
    assert status(None, {"jobs": jobs, "current": 0, "world": rendered}, progress) == "Rendering the world"
    nishita = bake_inputs.NishitaWorld("World", "Sky Texture", {})
    assert status(None, {"jobs": jobs, "current": 0, "world": nishita}, progress) == "Computing the sky"


def test_a_bake_is_still_baked_after_saving_and_reopening(clean_scene, tmp_path):
    """The fingerprint reads only what a .blend keeps: the first save (which moves the snow's file next to the
    .blend) and reopening leave the bake as it was."""
    world = bpy.data.worlds.new("Sky")
    world.use_nodes = True
    tree = world.node_tree
    sky = tree.nodes.new("ShaderNodeTexSky")
    environment = tree.nodes.new("ShaderNodeTexEnvironment")
    environment.image = bpy.data.images.new("Studio", 8, 4, float_buffer=True)
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    tree.links.new(sky.outputs["Color"], mix.inputs["A"])
    tree.links.new(environment.outputs["Color"], mix.inputs["B"])
    tree.links.new(mix.outputs["Result"], tree.nodes["Background"].inputs["Color"])
    bpy.context.scene.world = world
    add_sun()
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.05)  # into the session's cache folder
    snow = bpy.context.object
    add_contract_grids(bake_state.snow_path(snow), uniform_source(S))
    bake.adopt_bake(snow, optics_with(12.0), dict(bake.bake_inputs.signature(bpy.context, snow),
                                     optics=bake_state.optics_digest(snow)), "test grids")
    assert state(snow) == ("BAKED", [])
    blend = str(tmp_path / "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    assert snow.data.filepath.startswith("//firn_cache/")  # moved next to the .blend
    assert state(snow) == ("BAKED", [])
    bpy.ops.wm.open_mainfile(filepath=blend)
    snow = bpy.data.objects["Snow"]
    assert state(snow) == ("BAKED", []) and materials.is_baked_material(materials.snow_material(snow))
