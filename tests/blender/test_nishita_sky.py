"""The core's Nishita sky (cpp/firn/transport/nishita_sky.h) against Cycles' own render of the same Sky Texture
(the world probe: bake/world_probe.py), and the add-on computing an exact Nishita world in the core."""

import math

import bpy
import numpy as np
import pytest

from firn.bake import inputs as bake_inputs, world_probe
from firn.common.core import firncore

# Sun elevation and rotation (deg) and the node's other settings; strength is the Background's.
CASES = {
    "default": dict(elevation=15.0, rotation=0.0),
    "high sun, thick air": dict(elevation=50.0, rotation=120.0, altitude=2000.0, air_density=1.5,
                                dust_density=3.0, ozone_density=2.0, strength=2.5),
    "sun near the horizon": dict(elevation=1.0, rotation=-60.0, dust_density=0.5),
    "mountain, clean air": dict(elevation=70.0, rotation=200.0, altitude=20000.0, dust_density=0.0,
                                sun_size=2.0, sun_intensity=0.5),
    "twilight": dict(elevation=-3.0, rotation=30.0),
}


def nishita_world(elevation=15.0, rotation=0.0, sun_size=0.545, strength=1.0, **settings):
    """A world of one Nishita Sky Texture -> Background -> World Output (angles in degrees)."""
    world = bpy.data.worlds.new("Nishita")
    world.use_nodes = True
    tree = world.node_tree
    sky = tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    sky.sun_elevation, sky.sun_rotation = math.radians(elevation), math.radians(rotation)
    sky.sun_size = math.radians(sun_size)
    for key, value in settings.items():
        setattr(sky, key, value)
    background = tree.nodes["Background"]
    background.inputs["Strength"].default_value = strength
    tree.links.new(sky.outputs["Color"], background.inputs["Color"])
    bpy.context.scene.world = world
    return world, sky


def core_sky(world):
    parameters = bake_inputs.nishita_parameters(world)
    assert parameters is not None
    return firncore.NishitaSky(**parameters)


def mean_relative_error(value, reference):
    """Per channel: sum |value - reference| / sum reference over the pixels Cycles sees light in."""
    return np.abs(value - reference).sum(axis=(0, 1)) / reference.sum(axis=(0, 1))


@pytest.mark.parametrize("case", CASES)
def test_sky_map_matches_cycles(clean_scene, case):
    world, node = nishita_world(**CASES[case])
    with world_probe.WorldProbe(world, 1) as probe:
        probe.world.node_tree.nodes[node.name].sun_disc = False  # the map is the sky without its disc
        cycles = probe.equirect(np.eye(3), samples=64)
    width, height = world_probe.SKY_MAP_SIZE
    core = core_sky(world).map(np.eye(3), width, height, samples=4)
    error = mean_relative_error(core, cycles)
    print(f"{case}: mean relative error R, G, B = {np.round(100 * error, 2)} %")
    # Measured 2026-11-23 (Blender 3.4.1, 64 samples per pixel): 0.4-1.2 % per channel, the most in red with
    # the sun near the horizon. Cycles reads its sky from a 512 x 128 table it interpolates (its rows a little
    # off the elevations they are looked up at); the core computes every direction.
    assert error.max() < 0.03


@pytest.mark.parametrize("case", [c for c in CASES if c != "twilight"])
def test_sun_disc_irradiance_matches_cycles(clean_scene, case):
    world, node = nishita_world(**CASES[case])
    sun = core_sky(world).sun()
    direction = bake_inputs.sky_sun_direction(node)
    assert sun.direction == pytest.approx(tuple(direction), abs=1e-6)
    assert sun.angular_diameter == pytest.approx(max(node.sun_size, 0.0005))
    field_of_view = world_probe.disc_field_of_view(node.sun_size)
    with world_probe.WorldProbe(world, 1) as probe:
        with_disc = probe.close_up(direction, field_of_view, size=64, samples=256)
        probe.world.node_tree.nodes[node.name].sun_disc = False
        without_disc = probe.close_up(direction, field_of_view, size=64, samples=256)
    cycles = bake_inputs.sun_irradiance(with_disc - without_disc, field_of_view)
    print(f"{case}: sun irradiance core {np.round(sun.irradiance, 4)}, Cycles {np.round(cycles, 4)} W/m^2")
    # Measured: within 0.17 % in every case and channel (Cycles' close-up: 64 x 64 pixels, 256 samples each).
    assert sun.irradiance == pytest.approx(tuple(cycles), rel=0.01)


def test_twilight_has_no_sun(clean_scene):
    world, _node = nishita_world(**CASES["twilight"])
    assert core_sky(world).sun() is None


# --- the add-on -----------------------------------------------------------------------------------------------

def test_only_the_exact_chain_is_computed_by_the_core(clean_scene):
    world, node = nishita_world(elevation=30.0, rotation=40.0, strength=3.0, altitude=500.0)
    parameters = bake_inputs.nishita_parameters(world)
    assert parameters["strength"] == pytest.approx(3.0) and parameters["altitude"] == pytest.approx(500.0)
    assert parameters["sun_elevation"] == pytest.approx(math.radians(30.0))
    tree = world.node_tree
    background = tree.nodes["Background"]

    value = tree.nodes.new("ShaderNodeValue")
    tree.links.new(value.outputs[0], background.inputs["Strength"])
    assert bake_inputs.nishita_parameters(world) is None  # a linked strength
    tree.links.remove(background.inputs["Strength"].links[0])
    assert bake_inputs.nishita_parameters(world) is not None

    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    tree.links.new(coordinates.outputs["Generated"], node.inputs["Vector"])
    assert bake_inputs.nishita_parameters(world) is None  # a mapped sky
    tree.links.remove(node.inputs["Vector"].links[0])

    node.texture_mapping.rotation[2] = 0.5
    assert bake_inputs.nishita_parameters(world) is None  # the node's own texture mapping turns the sky
    node.texture_mapping.rotation[2] = 0.0

    node.sky_type = "HOSEK_WILKIE"
    assert bake_inputs.nishita_parameters(world) is None
    node.sky_type = "NISHITA"
    node.mute = True
    assert bake_inputs.nishita_parameters(world) is None
    node.mute = False
    assert bake_inputs.nishita_parameters(world) is not None


def test_a_nishita_world_is_computed_without_rendering(clean_scene):
    """gather_sky and the bake's world request: a Nishita world is the core's map and sun, no Cycles render
    (no probe scene is made), in the snow's frame."""
    world, node = nishita_world(elevation=30.0, rotation=40.0)
    obj = bpy.data.objects.new("Frame", None)
    obj.rotation_euler = (0.0, 0.0, math.radians(90))
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.update()
    frame = bake_inputs.Frame(obj)
    scenes_before = len(bpy.data.scenes)
    request = bake_inputs.world_request(bpy.context.scene, [frame])
    assert isinstance(request, bake_inputs.NishitaWorld)
    sky, suns = request.light(frame)
    assert len(bpy.data.scenes) == scenes_before
    assert sky.map.shape == (world_probe.SKY_MAP_SIZE[1], world_probe.SKY_MAP_SIZE[0], 3)
    assert sky.radiance == (1.0, 1.0, 1.0) and sky.description.startswith("Nishita")
    expected = firncore.NishitaSky(**bake_inputs.nishita_parameters(world))
    # The map is in the object's frame: its +X (u = 1/2) looks along the world's +Y (u = 1/4), a quarter turn of
    # the world's map.
    height, width = sky.map.shape[:2]
    world_map = expected.map(np.eye(3), width, height, samples=bake_inputs.SKY_MAP_SAMPLES)
    assert np.allclose(sky.map, np.roll(world_map, width // 4, axis=1), rtol=1e-4, atol=1e-6)
    assert len(suns) == 1
    assert suns[0].direction == pytest.approx(frame.direction(bake_inputs.sky_sun_direction(node)), abs=1e-6)
    assert suns[0].irradiance == pytest.approx(expected.sun().irradiance)
    here_sky, here_suns, _warnings = bake_inputs.gather_sky(bpy.context.scene, frame)
    assert np.array_equal(here_sky.map, sky.map) and here_suns == suns


@pytest.mark.parametrize("setting, value", [("altitude", 1500.0), ("ozone_density", 2.0), ("sun_rotation", 1.0),
                                            ("sun_disc", False)])
def test_a_changed_nishita_setting_changes_the_bakes_sky_signature(clean_scene, setting, value):
    """bake/state.py marks a bake stale when bake_inputs.signature's "sky" digest changes."""
    world, node = nishita_world()
    before = bake_inputs.digest(bake_inputs.world_signature(world))
    setattr(node, setting, value)
    assert bake_inputs.digest(bake_inputs.world_signature(world)) != before


def test_a_changed_strength_changes_the_bakes_sky_signature(clean_scene):
    world, _node = nishita_world()
    before = bake_inputs.digest(bake_inputs.world_signature(world))
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 2.0
    assert bake_inputs.digest(bake_inputs.world_signature(world)) != before
