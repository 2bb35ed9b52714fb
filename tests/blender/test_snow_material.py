"""Snow material: optics settings on obj.firn, the Principled Volume they drive (checked by rendering with
Cycles), presets, operators and the panels."""

import math
import os
import pathlib
import re
import types

import bpy
import numpy as np
import pytest

from firn.material import nodes as materials, operators as snow_material, optics, ui as snow_material_ui
from firn.common.core import firncore

REPO = pathlib.Path(__file__).resolve().parents[2]
RHO_ICE = 917.0  # kg/m^3


# --- helpers ---------------------------------------------------------------------------------------------

def snow_slab(directory, density, voxel=0.01, size=(32, 32, 5), name="Snow"):
    """A volume object reading a uniform slab of `density` (kg/m^3), size voxels of `voxel` metres, as snow."""
    import pyopenvdb

    grid = pyopenvdb.FloatGrid()
    grid.name = "density"
    grid.transform = pyopenvdb.createLinearTransform(voxelSize=voxel)
    accessor = grid.getAccessor()
    for i in range(size[0]):
        for j in range(size[1]):
            for k in range(size[2]):
                accessor.setValueOn((i, j, k), density)  # voxel by voxel: Cycles renders tiles as empty
    path = os.path.join(directory, f"{name}.vdb")
    pyopenvdb.write(path, grids=[grid])

    volume = bpy.data.volumes.new(name)
    volume.filepath = path
    volume.render.precision = "FULL"
    volume.render.clipping = 0.0
    obj = bpy.data.objects.new(name, volume)
    bpy.context.scene.collection.objects.link(obj)
    obj.firn.is_snow = True
    bpy.context.view_layer.objects.active = obj
    return obj


def volume_node(obj):
    return materials.snow_material(obj).node_tree.nodes["Firn Volume"]


def material_optics(obj):
    """(extinction per density, albedo, g) as the material holds them."""
    nodes = materials.snow_material(obj).node_tree.nodes
    return (nodes["Firn Extinction"].inputs[1].default_value,
            tuple(nodes["Firn Volume"].inputs["Color"].default_value)[:3],
            nodes["Firn Volume"].inputs["Anisotropy"].default_value)


def documented_presets():
    """{display name: {property: value}} from the presets table in docs/optics.md."""
    text = (REPO / "docs" / "optics.md").read_text(encoding="utf-8")
    table = text[text.index("| Preset | Grain radius"):].split("\n\n")[0].splitlines()[2:]
    presets = {}
    for row in table:
        cells = [cell.strip() for cell in row.strip("|").split("|")]
        presets[cells[0]] = {
            "grain_radius": float(cells[1]) * 1e-6,
            "impurity_black_carbon": float(cells[2]),
            "impurity_dust": float(cells[3]),
            "liquid_water": float(cells[4]),
            "absorption_enhancement": 1.6,
            "anisotropy": 0.845,
        }
    return presets


def run_preset(path):
    result = bpy.ops.script.execute_preset(filepath=path, menu_idname="FIRN_MT_snow_material_presets")
    assert result == {"FINISHED"}


# --- settings and material -------------------------------------------------------------------------------

def test_settings_have_the_documented_names(clean_scene, tmp_path):
    settings = snow_slab(str(tmp_path), 250.0).firn
    assert settings.optics_mode == "PHYSICAL"
    assert settings.grain_radius == pytest.approx(100e-6)
    assert settings.mean_density == 250.0
    assert settings.anisotropy == pytest.approx(0.845)
    for name in ("impurity_black_carbon", "impurity_dust", "liquid_water", "extinction_per_density", "albedo",
                 "absorption_enhancement"):
        assert hasattr(settings, name), name
    # Custom optics start from the physical defaults.
    default = firncore.optics(grain_radius=100e-6, density=250.0)
    assert settings.extinction_per_density == pytest.approx(default.extinction_per_density, rel=1e-6)
    assert tuple(settings.albedo) == pytest.approx(default.albedo, abs=1e-7)
    settings.grain_radius_um = 250.0  # the panel's view in micrometres
    assert settings.grain_radius == pytest.approx(250e-6)


def test_material_is_the_optics(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 250.0)
    obj.firn.grain_radius = 200e-6
    obj.firn.impurity_black_carbon = 50.0
    material = materials.ensure_snow_material(obj)
    assert materials.is_snow_material(material) and obj.material_slots[0].link == "OBJECT"
    expected = firncore.optics(grain_radius=200e-6, density=250.0, black_carbon=50e-9)
    k, albedo, g = material_optics(obj)
    assert k == pytest.approx(3 / (2 * RHO_ICE * 200e-6), rel=1e-6)
    assert albedo == pytest.approx(expected.albedo, abs=1e-7)  # Blender stores float32
    assert g == pytest.approx(0.845)

    tree = material.node_tree
    volume = tree.nodes["Firn Volume"]
    assert volume.inputs["Density Attribute"].default_value == ""  # else Cycles multiplies by the grid twice
    assert tuple(volume.inputs["Absorption Color"].default_value)[:3] == (0.0, 0.0, 0.0)
    density_link = volume.inputs["Density"].links[0]
    assert density_link.from_node.name == "Firn Extinction"
    attribute = tree.nodes["Firn Extinction"].inputs[0].links[0].from_node
    assert attribute.attribute_name == "density"
    assert tree.nodes["Firn Output"].inputs["Volume"].links[0].from_node == volume


def test_material_updates_live(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 250.0)
    materials.ensure_snow_material(obj)
    settings = obj.firn

    settings.grain_radius = 500e-6
    assert material_optics(obj)[0] == pytest.approx(3 / (2 * RHO_ICE * 500e-6), rel=1e-6)
    before = material_optics(obj)[1]
    settings.impurity_black_carbon = 500.0
    assert all(a < b for a, b in zip(material_optics(obj)[1], before))
    settings.anisotropy = 0.7
    assert material_optics(obj)[2] == pytest.approx(0.7)

    settings.optics_mode = "CUSTOM"
    settings.extinction_per_density = 12.5
    settings.albedo = (0.2, 0.5, 0.8)
    k, albedo, g = material_optics(obj)
    assert (k, albedo, g) == (pytest.approx(12.5), pytest.approx((0.2, 0.5, 0.8)), pytest.approx(0.7))

    # Settings that are not snow leave the material as it was; the panel says why.
    settings.optics_mode = "PHYSICAL"
    good = material_optics(obj)
    settings.liquid_water = 0.3  # 300 kg/m^3 of water in 250 kg/m^3 of snow
    assert material_optics(obj) == good
    assert "leaving no ice" in optics.derived(settings).error


def test_material_belongs_to_its_object(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 250.0)
    material = materials.ensure_snow_material(obj)
    twin = obj.copy()  # shares the volume data and, at first, the material
    bpy.context.scene.collection.objects.link(twin)
    assert materials.snow_material(twin) == material
    twin.firn.grain_radius = 1e-3
    assert materials.snow_material(twin) != material
    assert material_optics(obj)[0] == pytest.approx(3 / (2 * RHO_ICE * 100e-6), rel=1e-6)
    assert material_optics(twin)[0] == pytest.approx(3 / (2 * RHO_ICE * 1e-3), rel=1e-6)


def test_assign_restores_the_material(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 250.0)
    materials.ensure_snow_material(obj)
    obj.material_slots[0].material = bpy.data.materials.new("Mine")
    assert materials.snow_material(obj) is None
    obj.firn.grain_radius = 300e-6  # the user's own material is not touched
    assert not bpy.data.materials["Mine"].use_nodes
    assert bpy.ops.firn.snow_material_assign() == {"FINISHED"}
    assert material_optics(obj)[0] == pytest.approx(3 / (2 * RHO_ICE * 300e-6), rel=1e-6)


def test_copy_to_custom_keeps_the_look(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 400.0)
    obj.firn.mean_density = 400.0
    obj.firn.liquid_water = 0.04
    materials.ensure_snow_material(obj)
    k, albedo, g = material_optics(obj)
    assert bpy.ops.firn.snow_optics_to_custom() == {"FINISHED"}
    assert obj.firn.optics_mode == "CUSTOM"
    assert material_optics(obj)[0] == pytest.approx(k)
    assert material_optics(obj)[1] == pytest.approx(albedo, abs=1e-7)
    assert material_optics(obj)[2] == pytest.approx(g)
    assert not bpy.ops.firn.snow_optics_to_custom.poll()  # already custom


# --- presets ---------------------------------------------------------------------------------------------

def test_presets_load_and_set_the_documented_values(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 300.0)
    materials.ensure_snow_material(obj)
    documented = documented_presets()
    files = dict(snow_material.preset_files())
    for required in ("Fresh Powder", "Settled Snow", "Wind Packed", "Wet Snow", "Old Snow and Firn", "Dirty Snow"):
        assert required in documented and required in files, required
    assert list(files)[:len(documented)] == list(documented)  # menu order is the documented order
    for name, values in documented.items():
        obj.firn.optics_mode = "CUSTOM"
        run_preset(files[name])
        assert obj.firn.optics_mode == "PHYSICAL"
        for prop, value in values.items():
            assert getattr(obj.firn, prop) == pytest.approx(value, rel=1e-6), (name, prop)
        assert "Sources" not in name and re.search(r"et al\.|ICSSG", pathlib.Path(files[name]).read_text()), name
        # The material follows the preset.
        assert material_optics(obj)[0] == pytest.approx(optics.volume_optics(obj.firn).extinction_per_density)
        assert optics.derived(obj.firn).error is None, name


def test_users_add_and_remove_their_own_presets(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 300.0)
    obj.firn.grain_radius = 333e-6
    obj.firn.impurity_dust = 42.0
    menu = bpy.types.FIRN_MT_snow_material_presets
    try:
        assert bpy.ops.firn.snow_material_preset_add(name="My Snow") == {"FINISHED"}
        files = dict(snow_material.preset_files())
        assert "My Snow" in files
        path = files["My Snow"]
        assert path.startswith(bpy.utils.user_resource("SCRIPTS"))  # survives reinstalling the add-on
        obj.firn.grain_radius = 50e-6
        obj.firn.impurity_dust = 0.0
        run_preset(path)
        assert obj.firn.grain_radius == pytest.approx(333e-6) and obj.firn.impurity_dust == pytest.approx(42.0)

        # Firn's own presets stay.
        run_preset(files["Fresh Powder"])
        assert menu.bl_label == "Fresh Powder"
        assert bpy.ops.firn.snow_material_preset_add(remove_active=True) == {"CANCELLED"}
        assert os.path.exists(files["Fresh Powder"])

        run_preset(path)
        assert menu.bl_label == "My Snow"
        assert bpy.ops.firn.snow_material_preset_add(remove_active=True) == {"FINISHED"}
        assert not os.path.exists(path)
        assert "My Snow" not in dict(snow_material.preset_files())
    finally:
        for _, path in snow_material.preset_files():
            if os.path.basename(path) == "My_Snow.py":
                os.remove(path)


# --- panels ----------------------------------------------------------------------------------------------

class RecordingLayout:
    """Stands in for bpy.types.UILayout: checks every property, operator and menu a panel draws."""

    def __init__(self, log):
        self.log = log

    def __getattr__(self, name):  # row, column, box, split, ...: a sub-layout
        return lambda *args, **kwargs: RecordingLayout(self.log)

    def __setattr__(self, name, value):
        object.__setattr__(self, name, value)

    def prop(self, data, name, **_kwargs):
        assert name in data.bl_rna.properties, name
        self.log["props"].append(name)

    def label(self, text="", **_kwargs):
        self.log["labels"].append(text)

    def operator(self, idname, **_kwargs):
        category, name = idname.split(".")
        assert hasattr(getattr(bpy.ops, category), name), idname
        self.log["operators"].append(idname)
        return types.SimpleNamespace()

    def menu(self, idname, **_kwargs):
        assert hasattr(bpy.types, idname), idname
        self.log["menus"].append(idname)


def draw_log(obj):
    log = {"props": [], "labels": [], "operators": [], "menus": []}
    snow_material_ui.draw_snow_material(RecordingLayout(log), obj)
    return log


def test_panels_show_snow_objects_only(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 250.0)
    for panel in (bpy.types.FIRN_PT_snow_material, bpy.types.FIRN_PT_sidebar_snow_material):
        assert panel.poll(types.SimpleNamespace(object=obj))
        obj.firn.is_snow = False
        assert not panel.poll(types.SimpleNamespace(object=obj))
        assert not panel.poll(types.SimpleNamespace(object=None))
        obj.firn.is_snow = True
    assert bpy.types.FIRN_PT_snow_material.bl_context == "object"
    assert bpy.types.FIRN_PT_sidebar_snow_material.bl_parent_id == "FIRN_PT_sidebar"


def test_panel_draws_parameters_and_derived_values(clean_scene, tmp_path):
    obj = snow_slab(str(tmp_path), 250.0)
    materials.ensure_snow_material(obj)
    log = draw_log(obj)
    assert "FIRN_MT_snow_material_presets" in log["menus"]
    assert {"firn.snow_material_preset_add", "firn.snow_optics_to_custom"} <= set(log["operators"])
    assert {"optics_mode", "grain_radius_um", "impurity_black_carbon", "impurity_dust", "liquid_water",
            "absorption_enhancement", "anisotropy", "mean_density"} <= set(log["props"])
    labels = " | ".join(log["labels"])
    sigma_t = 3 * 250.0 / (2 * RHO_ICE * 100e-6)
    assert f"{sigma_t:.4g} 1/m" in labels
    assert re.search(r"Diffusion cm", labels) and re.search(r"ℓ\*  [0-9.]+ mm", labels)

    obj.firn.optics_mode = "CUSTOM"
    assert {"extinction_per_density", "albedo"} <= set(draw_log(obj)["props"])

    obj.firn.optics_mode = "PHYSICAL"
    obj.firn.liquid_water = 0.3
    assert "leaving no ice" in " ".join(draw_log(obj)["labels"])


# --- Cycles renders the optics -------------------------------------------------------------------------------

def render_mean(scene, directory, samples):
    """Mean linear RGB of a 32 x 32 Cycles CPU render."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = 32
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = os.path.join(directory, "render.exr")
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(scene.render.filepath, check_existing=False)
    pixels = np.array(image.pixels[:]).reshape(-1, 4)
    bpy.data.images.remove(image)
    return pixels[:, :3].mean(axis=0)


def look_down_at_slab(scene):
    """Orthographic camera looking straight down at the middle of a 32 cm slab."""
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 0.16
    camera.location = (0.16, 0.16, 1.0)
    scene.collection.objects.link(camera)
    scene.camera = camera


def world(scene, camera_only):
    """White background; if camera_only, it lights nothing (Light Path: Is Camera Ray), else black."""
    scene.world = bpy.data.worlds.new("World")
    scene.world.use_nodes = True
    nodes, links = scene.world.node_tree.nodes, scene.world.node_tree.links
    background = nodes["Background"]
    background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    background.inputs["Strength"].default_value = 1.0 if camera_only else 0.0
    if camera_only:
        black = nodes.new("ShaderNodeBackground")
        black.inputs["Strength"].default_value = 0.0
        mix = nodes.new("ShaderNodeMixShader")
        links.new(nodes.new("ShaderNodeLightPath").outputs["Is Camera Ray"], mix.inputs["Fac"])
        links.new(black.outputs["Background"], mix.inputs[1])
        links.new(background.outputs["Background"], mix.inputs[2])
        links.new(mix.outputs["Shader"], nodes["World Output"].inputs["Surface"])


def test_cycles_transmission_follows_sigma_t(clean_scene, tmp_path):
    # A 5 cm slab of snow (r = 100 um) at a grid density of 1.2 kg/m^3 in front of a white background that lights
    # nothing: each pixel is the slab's transmittance exp(-sigma_t L), sigma_t = 3 rho / (2 rho_ice r).
    # Cycles estimates it by sampling free paths (a pixel sample passes or not); with its stratified samples the
    # mean of 32 x 32 x 256 samples lands within 0.01 % (seeds 0-3).
    scene = clean_scene
    obj = snow_slab(str(tmp_path), 1.2)
    materials.ensure_snow_material(obj)
    look_down_at_slab(scene)
    world(scene, camera_only=True)
    scene.cycles.max_bounces = 0
    sigma_t = 3 * 1.2 / (2 * RHO_ICE * 100e-6)
    expected = math.exp(-sigma_t * 0.05)  # 0.375
    assert render_mean(scene, str(tmp_path), samples=256) == pytest.approx([expected] * 3, rel=0.005)


def single_scattering(g, sun_zenith, tau, albedo, irradiance):
    """Radiance seen straight down from a slab of optical depth tau lit by a sun: only single scattering
    (exact for volume bounces = 0). Henyey-Greenstein phase function at the angle between the sun's light and
    the view direction."""
    mu_s = math.cos(sun_zenith)
    cos_theta = -mu_s  # light travels down, the scattered light up to the camera
    phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * cos_theta) ** 1.5)
    path = 1 + 1 / mu_s
    return [irradiance * a * phase * (1 - math.exp(-tau * path)) / path for a in albedo]


def test_cycles_single_scattering_follows_albedo_and_anisotropy(clean_scene, tmp_path):
    # Custom optics, 10 /m in a 5 cm slab, lit by a sun 30 deg from the zenith against a black sky. Cycles renders
    # single scattering exactly with volume bounces = 0 (measured within 0.05 % here).
    scene = clean_scene
    obj = snow_slab(str(tmp_path), 2.0)
    obj.firn.optics_mode = "CUSTOM"
    obj.firn.extinction_per_density = 5.0  # m^2/kg: sigma_t = 10 /m, tau = 0.5
    obj.firn.albedo = (0.2, 0.5, 0.8)
    materials.ensure_snow_material(obj)
    look_down_at_slab(scene)
    world(scene, camera_only=False)
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 10.0  # W/m^2
    sun.data.angle = 0.0
    sun.rotation_euler = (math.radians(30), 0.0, 0.0)
    scene.collection.objects.link(sun)
    scene.cycles.volume_bounces = 0

    rendered = {}
    for g in (0.0, 0.5):
        obj.firn.anisotropy = g
        rendered[g] = render_mean(scene, str(tmp_path), samples=64)
        expected = single_scattering(g, math.radians(30), 0.5, (0.2, 0.5, 0.8), 10.0)
        assert rendered[g] == pytest.approx(expected, rel=0.01), g
    # Colour: the channels scale with the albedo (the same extinction in all three).
    assert rendered[0.0][0] / rendered[0.0][2] == pytest.approx(0.25, rel=0.005)
    # Positive g scatters forward: seen against the light's direction, the slab darkens to p(0.5) / p(0).
    p_ratio = single_scattering(0.5, math.radians(30), 0.5, (1,), 1)[0] / single_scattering(
        0.0, math.radians(30), 0.5, (1,), 1)[0]
    assert rendered[0.5][1] / rendered[0.0][1] == pytest.approx(p_ratio, rel=0.01)
