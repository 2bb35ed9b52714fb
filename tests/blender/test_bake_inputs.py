"""What the bake reads from Blender: suns and lamps, the world (uniform, rendered into an equirect map,
Nishita sun discs), occluders with their albedo, and the snow's frame. No core bake needed."""

import math
import os
import threading

import bpy
import numpy as np
import pytest

from bake_helpers import uniform_world, volume_object
from firn.bake import inputs as bake_inputs, world_probe
from firn.common.errors import UserError


def identity_frame():
    obj = bpy.data.objects.new("Frame", None)
    return bake_inputs.Frame(obj)


def add_lamp(kind, name, **settings):
    light = bpy.data.lights.new(name, kind)
    obj = bpy.data.objects.new(name, light)
    bpy.context.scene.collection.objects.link(obj)
    for key, value in settings.items():
        setattr(light if hasattr(light, key) else obj, key, value)
    return obj


def direction_from_uv(u, v):
    """cpp/firn/transport/lights.h EnvironmentMap::directionFromUv: u = 0.5 looks along +X, u = 0.25 along +Y, v = 1 up."""
    phi = 2 * math.pi * (0.5 - u)
    elevation = math.pi * (v - 0.5)
    return np.array([math.cos(elevation) * math.cos(phi), math.cos(elevation) * math.sin(phi), math.sin(elevation)])


def direction_world():
    """A world whose radiance encodes the direction it comes from: (d + 1) / 2 per channel."""
    world = bpy.data.worlds.new("Direction")
    world.use_nodes = True
    tree = world.node_tree
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    encode = tree.nodes.new("ShaderNodeVectorMath")
    encode.operation = "MULTIPLY_ADD"
    encode.inputs[1].default_value = (0.5, 0.5, 0.5)
    encode.inputs[2].default_value = (0.5, 0.5, 0.5)
    tree.links.new(coordinates.outputs["Generated"], encode.inputs[0])
    tree.links.new(encode.outputs["Vector"], tree.nodes["Background"].inputs["Color"])
    bpy.context.scene.world = world
    return world


def nishita_world(elevation, rotation):
    """A Nishita sky whose Strength comes from a Value node: not the exact chain the core computes
    (test_nishita_sky.py), so Cycles renders it through the world probe that these tests test."""
    world = bpy.data.worlds.new("Nishita")
    world.use_nodes = True
    tree = world.node_tree
    sky = tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    sky.sun_elevation, sky.sun_rotation = elevation, rotation
    background = tree.nodes["Background"]
    tree.links.new(sky.outputs["Color"], background.inputs["Color"])
    strength = tree.nodes.new("ShaderNodeValue")
    strength.outputs[0].default_value = 1.0
    tree.links.new(strength.outputs[0], background.inputs["Strength"])
    bpy.context.scene.world = world
    return world, sky


# --- suns -----------------------------------------------------------------------------------------------------

def test_sun_direction_irradiance_and_angle(clean_scene):
    sun = add_lamp("SUN", "Sun", energy=3.0, color=(1.0, 0.5, 0.25), angle=0.1)
    sun.rotation_euler = (math.radians(30), 0.0, math.radians(45))
    bpy.context.view_layer.update()
    suns, lamps = bake_inputs.gather_lights(bake_inputs.lamp_objects(bpy.context.view_layer), identity_frame())
    assert lamps == [] and len(suns) == 1
    # Light travels along the lamp's -Z; towards the sun is +Z: Rz(45) Rx(30) (0, 0, 1) by hand.
    expected = (math.sin(math.radians(30)) * math.sin(math.radians(45)),
                -math.sin(math.radians(30)) * math.cos(math.radians(45)), math.cos(math.radians(30)))
    assert suns[0].direction == pytest.approx(expected, abs=1e-6)
    assert suns[0].irradiance == pytest.approx((3.0, 1.5, 0.75))  # W/m^2 = Strength × Color
    assert suns[0].angular_diameter == pytest.approx(0.1)


def test_scaled_lamp_still_gives_a_unit_direction(clean_scene):
    sun = add_lamp("SUN", "Sun", energy=1.0)
    sun.scale = (3.0, 3.0, 0.2)
    bpy.context.view_layer.update()
    (found,), _ = bake_inputs.gather_lights([sun], identity_frame())
    assert found.direction == pytest.approx((0.0, 0.0, 1.0), abs=1e-9)


def test_point_spot_and_area_lamps_as_cycles_emits_them(clean_scene):
    """Emission by Cycles 3.4's conventions (measured there: test_lamps.py): I = P / 4π for points and spots,
    L = P / (4 A) for area lamps, whose size follows the object's scale; they shine along their local -Z."""
    add_lamp("POINT", "Bulb", energy=100.0, color=(1.0, 0.5, 0.25), shadow_soft_size=0.1, location=(1, 2, 3))
    spot = add_lamp("SPOT", "Spot", energy=40.0, spot_size=math.radians(60), spot_blend=0.3)
    spot.rotation_euler = (math.radians(90), 0.0, 0.0)  # -Z turns to +Y
    panel = add_lamp("AREA", "Panel", energy=8.0, shape="RECTANGLE", size=2.0, size_y=0.5)
    panel.scale = (1.0, 2.0, 1.0)
    add_lamp("AREA", "Disc", energy=math.pi, shape="DISK", size=2.0)
    add_lamp("POINT", "Off", energy=0.0)
    no_volumes = add_lamp("POINT", "Surfaces only", energy=10.0)
    no_volumes.visible_volume_scatter = False
    bpy.context.view_layer.update()
    suns, lamps = bake_inputs.gather_lights(bake_inputs.lamp_objects(bpy.context.view_layer), identity_frame())
    found = {lamp.name: lamp for lamp in lamps}
    assert suns == [] and sorted(found) == ["Bulb", "Disc", "Panel", "Spot"]
    bulb = found["Bulb"]
    assert bulb.shape == "POINT" and bulb.position == pytest.approx((1, 2, 3)) and bulb.radius == pytest.approx(0.1)
    assert bulb.emission == pytest.approx(tuple(100.0 / (4 * math.pi) * c for c in (1.0, 0.5, 0.25)))
    assert found["Spot"].axis == pytest.approx((0.0, 1.0, 0.0), abs=1e-6)
    assert (found["Spot"].spot_angle, found["Spot"].spot_blend) == pytest.approx((math.radians(60), 0.3))
    assert found["Panel"].shape == "RECTANGLE" and found["Panel"].size == pytest.approx((2.0, 1.0))
    assert found["Panel"].emission == pytest.approx((8.0 / (4 * 2.0),) * 3)
    assert found["Disc"].shape == "ELLIPSE" and found["Disc"].emission == pytest.approx((0.25,) * 3)  # A = π


def test_lamps_hidden_from_renders_or_excluded_do_not_light(clean_scene):
    hidden = add_lamp("SUN", "Hidden", energy=1.0)
    hidden.hide_render = True
    collection = bpy.data.collections.new("Excluded")
    bpy.context.scene.collection.children.link(collection)
    excluded = bpy.data.objects.new("Excluded Sun", bpy.data.lights.new("Excluded Sun", "SUN"))
    collection.objects.link(excluded)
    bpy.context.view_layer.layer_collection.children["Excluded"].exclude = True
    shown = add_lamp("SUN", "Shown", energy=1.0)
    shown.hide_set(True)  # hidden in the viewport only: it still renders, so it still lights the bake
    assert [obj.name for obj in bake_inputs.lamp_objects(bpy.context.view_layer)] == ["Shown"]


def test_sun_wider_than_90_degrees_is_refused(clean_scene):
    sun = add_lamp("SUN", "Wide", energy=1.0, angle=math.radians(120))
    with pytest.raises(UserError, match="up to 90"):
        bake_inputs.gather_lights([sun], identity_frame())


# --- world ----------------------------------------------------------------------------------------------------

def test_uniform_worlds_are_read_without_rendering(clean_scene):
    world = uniform_world((0.2, 0.4, 0.6))
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 2.5
    sky, suns, warnings = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert sky.map is None and suns == [] and warnings == []
    assert sky.radiance == pytest.approx((0.5, 1.0, 1.5))  # W/m^2/sr = Color × Strength

    world.use_nodes = False
    world.color = (0.1, 0.2, 0.3)
    sky, _, _ = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert sky.map is None and sky.radiance == pytest.approx((0.1, 0.2, 0.3))

    bpy.context.scene.world = None
    sky, _, _ = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert sky.map is None and sky.radiance == (0.0, 0.0, 0.0)


def test_node_world_becomes_an_equirect_map_in_the_core_convention(clean_scene):
    direction_world()
    images_before, scenes_before = len(bpy.data.images), len(bpy.data.scenes)
    sky, suns, _ = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert suns == [] and sky.radiance == (1.0, 1.0, 1.0)
    height, width = sky.map.shape[:2]
    assert (width, height) == world_probe.SKY_MAP_SIZE and sky.map.dtype == np.float32
    decoded = 2.0 * sky.map - 1.0  # the direction each pixel's radiance came from
    # Pixel (column i, row j; row 0 at the bottom) is centred at ((i + 1/2) / W, (j + 1/2) / H).
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    expected = np.stack(np.broadcast_arrays(*(
        np.array([direction_from_uv(uu, vv) for uu in u]) for vv in v)), axis=0)
    # The box filter averages each pixel's footprint (2.8 degrees): a small shortening of the unit vector.
    assert np.abs(decoded - expected).max() < 0.01
    # +X (u = 0.5), +Y (u = 0.25), zenith (top row), read as a user would.
    middle = height // 2
    assert decoded[middle, width // 2] == pytest.approx((1, 0, 0), abs=0.03)
    assert decoded[middle, width // 4] == pytest.approx((0, 1, 0), abs=0.03)
    assert decoded[height - 1].mean(axis=0) == pytest.approx((0, 0, 1), abs=0.01)
    assert decoded[0].mean(axis=0) == pytest.approx((0, 0, -1), abs=0.01)
    # The probe scene, its world copy and images are gone.
    assert len(bpy.data.scenes) == scenes_before
    assert len(bpy.data.images) <= images_before + 1  # "Render Result" may now exist


def test_sky_map_turns_with_a_rotated_volume(clean_scene, tmp_path):
    direction_world()
    obj = volume_object(str(tmp_path / "v.vdb"), rotation=(0.0, 0.0, math.radians(90)))
    bpy.context.view_layer.update()
    sky, _, _ = bake_inputs.gather_sky(bpy.context.scene, bake_inputs.Frame(obj))
    height, width = sky.map.shape[:2]
    decoded = 2.0 * sky.map - 1.0
    # The object's +X is world +Y: the map's +X pixel sees the world's +Y radiance.
    assert decoded[height // 2, width // 2] == pytest.approx((0, 1, 0), abs=0.03)
    assert decoded[height // 2, width // 4] == pytest.approx((-1, 0, 0), abs=0.03)


def test_nishita_sun_disc_becomes_a_sun(clean_scene):
    elevation, rotation = math.radians(30), math.radians(40)
    world, node = nishita_world(elevation, rotation)
    sky, suns, warnings = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert warnings == [] and len(suns) == 1
    sun = suns[0]
    assert sun.angular_diameter == pytest.approx(node.sun_size)
    assert node.sun_disc  # the user's world is untouched

    # Independently: a panorama of a 4 x 4 degree window around the expected sun, with and without its disc,
    # in 0.125 degree pixels (the disc is 0.545 degrees across). The brightest pixel gives the direction; the
    # difference summed over the pixels' solid angles, dlon (sin lat1 - sin lat0), gives the irradiance.
    expected = bake_inputs.sky_sun_direction(node)
    longitude, latitude = math.atan2(expected.y, expected.x), math.asin(expected.z)
    half, pixels = math.radians(2.0), 32
    with world_probe.WorldProbe(world, 1) as probe:
        probe.equirect(np.eye(3), (1, 1), samples=1)  # sets up the panoramic camera
        cycles = probe.camera.data.cycles
        # Cycles turns the longitude range the other way: azimuth = -(longitude_min + u (max - min)).
        cycles.longitude_min, cycles.longitude_max = -longitude - half, -longitude + half
        cycles.latitude_min, cycles.latitude_max = latitude - half, latitude + half
        with_disc = probe._render((pixels, pixels), 64)
        probe.world.node_tree.nodes[node.name].sun_disc = False
        without_disc = probe._render((pixels, pixels), 64)
    row, column = np.unravel_index(np.argmax(with_disc.sum(axis=2)), (pixels, pixels))
    step = 2 * half / pixels
    peak_latitude = latitude - half + (row + 0.5) * step  # rows from the bottom
    peak_longitude = longitude + half - (column + 0.5) * step  # longitude falls to the right (u = 0.5 - lon / 2 pi)
    peak = (math.cos(peak_latitude) * math.cos(peak_longitude), math.cos(peak_latitude) * math.sin(peak_longitude),
            math.sin(peak_latitude))
    assert np.degrees(math.acos(np.clip(np.dot(peak, sun.direction), -1, 1))) < 0.15
    edges = latitude - half + step * np.arange(pixels + 1)
    solid_angle = step * (np.sin(edges[1:]) - np.sin(edges[:-1]))
    irradiance = ((with_disc - without_disc) * solid_angle[:, None, None]).sum(axis=(0, 1))
    assert sun.irradiance == pytest.approx(tuple(irradiance), rel=0.01)  # measured 0.5 %
    # The map keeps the sky without the disc.
    assert sky.map.max() < 0.01 * max(sun.irradiance) / (math.pi * (node.sun_size / 2) ** 2)


def render_in_worker(request, cancelled=lambda: False):
    """world_probe.render as the bake's worker thread calls it: off the main thread, so by a child Blender."""
    outcome = {}

    def work():
        try:
            outcome["rendering"] = world_probe.render(request, cancelled)
        except world_probe.RenderError as error:
            outcome["error"] = error

    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    return outcome


def test_a_child_blender_renders_the_world_as_the_main_thread_does(clean_scene):
    """From a worker thread the world is rendered by a child Blender (the UI keeps its main thread): the same
    sky map and the same sun as a render in place, and its files are removed."""
    nishita_world(math.radians(30), math.radians(40))
    frame = identity_frame()
    here_sky, here_suns, _ = bake_inputs.gather_sky(bpy.context.scene, frame)
    world = bake_inputs.world_request(bpy.context.scene, [frame])
    outcome = render_in_worker(world.request)
    assert not os.path.exists(world.request.folder)
    world.rendering = outcome["rendering"]
    sky, suns = world.light(frame)
    # Cycles seeds each pixel alone: the same world, samples and seed give the same pixels in any process.
    assert np.allclose(sky.map, here_sky.map, rtol=1e-5, atol=1e-7)
    assert len(suns) == len(here_suns) == 1
    assert suns[0].irradiance == pytest.approx(here_suns[0].irradiance, rel=1e-5)
    assert suns[0].direction == pytest.approx(here_suns[0].direction)


def test_a_child_render_stops_on_cancel_and_says_why_it_failed(clean_scene):
    direction_world()
    request = bake_inputs.world_request(bpy.context.scene, [identity_frame()]).request
    assert render_in_worker(request, cancelled=lambda: True) == {"rendering": None}
    assert not os.path.exists(request.folder)

    request = bake_inputs.world_request(bpy.context.scene, [identity_frame()]).request
    request.world = "Not There"
    error = render_in_worker(request)["error"]
    assert "Not There" in str(error) and "missing" in str(error)


def test_mapped_nishita_keeps_its_disc_in_the_map_and_says_so(clean_scene):
    world, node = nishita_world(math.radians(30), 0.0)
    mapping = world.node_tree.nodes.new("ShaderNodeTexCoord")
    world.node_tree.links.new(mapping.outputs["Generated"], node.inputs["Vector"])
    _sky, suns, warnings = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert suns == [] and any("stays in the sky map" in w for w in warnings)


def test_world_hidden_from_scattering_does_not_light(clean_scene):
    world = uniform_world((1.0, 1.0, 1.0))
    world.cycles_visibility.scatter = False
    sky, _, warnings = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert sky.radiance == (0.0, 0.0, 0.0) and sky.map is None and "volume scattering" in warnings[0]


@pytest.mark.parametrize("camera_sees, lights_with", [((1.0, 1.0, 1.0), (0.0, 0.0, 0.0)),
                                                     ((0.0, 0.0, 0.0), (0.2, 0.4, 0.6))])
def test_world_is_read_for_what_lights_not_what_the_camera_sees(clean_scene, camera_sees, lights_with):
    """A world behind Light Path > Is Camera Ray shows one colour to the camera and lights with another: the
    bake takes the light."""
    world = bpy.data.worlds.new("Backdrop")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    backdrop, light = nodes["Background"], nodes.new("ShaderNodeBackground")
    backdrop.inputs["Color"].default_value = (*camera_sees, 1.0)
    light.inputs["Color"].default_value = (*lights_with, 1.0)
    mix = nodes.new("ShaderNodeMixShader")
    links.new(nodes.new("ShaderNodeLightPath").outputs["Is Camera Ray"], mix.inputs["Fac"])
    links.new(light.outputs["Background"], mix.inputs[1])
    links.new(backdrop.outputs["Background"], mix.inputs[2])
    links.new(mix.outputs["Shader"], nodes["World Output"].inputs["Surface"])
    bpy.context.scene.world = world
    sky, _, _ = bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert sky.map.reshape(-1, 3).min(axis=0) == pytest.approx(lights_with, abs=1e-6)
    assert sky.map.reshape(-1, 3).max(axis=0) == pytest.approx(lights_with, abs=1e-6)
    assert nodes.get("Light Path") is not None  # the user's world keeps its nodes


def test_render_result_of_the_user_is_kept(clean_scene, tmp_path):
    """Rendering the world for the bake goes into a render slot of Firn's own, made once and reused."""
    bpy.context.scene.cycles.use_denoising = False
    bpy.ops.object.camera_add()
    bpy.context.scene.camera = bpy.context.object
    bpy.context.scene.render.engine = "CYCLES"
    bpy.context.scene.render.resolution_percentage = 1
    bpy.ops.render.render()  # the user's last render
    result = bpy.data.images["Render Result"]
    slots_before, active_before = len(result.render_slots), result.render_slots.active_index
    direction_world()
    for _ in range(2):
        bake_inputs.gather_sky(bpy.context.scene, identity_frame())
    assert len(result.render_slots) == slots_before + 1 and result.render_slots.active_index == active_before
    assert result.render_slots[slots_before].name == "Firn World Probe"


# --- occluders ------------------------------------------------------------------------------------------------

def principled(name, rgb):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*rgb, 1.0)
    return material


def test_albedo_from_principled_diffuse_viewport_or_grey(clean_scene):
    assert bake_inputs.diffuse_albedo(principled("Plain", (0.2, 0.4, 0.6))) == pytest.approx((0.2, 0.4, 0.6))

    textured = principled("Textured", (0.2, 0.4, 0.6))
    texture = textured.node_tree.nodes.new("ShaderNodeTexChecker")
    textured.node_tree.links.new(texture.outputs["Color"],
                                 textured.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
    textured.diffuse_color = (0.3, 0.3, 0.1, 1.0)
    assert bake_inputs.diffuse_albedo(textured) == pytest.approx((0.3, 0.3, 0.1))

    diffuse = bpy.data.materials.new("Diffuse")
    diffuse.use_nodes = True
    tree = diffuse.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    bsdf = tree.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (0.7, 0.1, 0.05, 1.0)
    tree.links.new(bsdf.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    assert bake_inputs.diffuse_albedo(diffuse) == pytest.approx((0.7, 0.1, 0.05))

    no_nodes = bpy.data.materials.new("Viewport")
    no_nodes.diffuse_color = (0.5, 0.25, 0.125, 1.0)
    assert bake_inputs.diffuse_albedo(no_nodes) == pytest.approx((0.5, 0.25, 0.125))
    assert bake_inputs.diffuse_albedo(None) == (0.8, 0.8, 0.8)


def test_occluders_per_object_and_material_in_world_space(clean_scene, tmp_path):
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(1.0, 2.0, 3.0))
    plane = bpy.context.object
    plane.data.materials.append(principled("Red", (0.8, 0.1, 0.1)))
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(5.0, 0.0, 0.0))
    cube = bpy.context.object
    cube.data.materials.append(principled("Blue", (0.1, 0.1, 0.8)))
    cube.data.materials.append(principled("Green", (0.1, 0.8, 0.1)))
    for index, polygon in enumerate(cube.data.polygons):
        polygon.material_index = 1 if index < 2 else 0
    bpy.ops.mesh.primitive_uv_sphere_add(location=(9, 0, 0))
    bpy.context.object.hide_render = True  # not in renders: no shadow
    bpy.ops.mesh.primitive_ico_sphere_add(location=(12, 0, 0))
    bpy.context.object.visible_shadow = False  # casts no shadow in Cycles
    snow = volume_object(str(tmp_path / "snow.vdb"))
    snow.firn.is_snow = True

    objects = bake_inputs.occluder_objects(bpy.context.view_layer)
    assert [obj.name for obj in objects] == [plane.name, cube.name]
    occluders = bake_inputs.gather_occluders(objects, bpy.context.evaluated_depsgraph_get(), identity_frame())
    by_name = {o.name: o for o in occluders}
    assert set(by_name) == {"Plane [Red]", "Cube [Blue]", "Cube [Green]"}
    red = by_name["Plane [Red]"]
    assert red.albedo == pytest.approx((0.8, 0.1, 0.1))
    assert red.vertices.dtype == np.float32 and red.triangles.dtype == np.uint32
    assert red.vertices.min(axis=0) == pytest.approx((0.0, 1.0, 3.0)) and len(red.triangles) == 2
    assert len(by_name["Cube [Green]"].triangles) == 4 and len(by_name["Cube [Blue]"].triangles) == 8
    for occluder in occluders:
        assert occluder.triangles.max() < len(occluder.vertices)


def test_occluders_and_suns_in_a_rotated_volume_frame(clean_scene, tmp_path):
    bpy.ops.mesh.primitive_plane_add(size=2.0, location=(3.0, 0.0, 0.0))
    sun = add_lamp("SUN", "Sun", energy=1.0)
    sun.rotation_euler = (math.radians(90), 0, 0)  # towards the sun: world -Y
    obj = volume_object(str(tmp_path / "v.vdb"), location=(1.0, 0.0, 0.0), rotation=(0, 0, math.radians(90)))
    obj.scale = (2.0, 2.0, 2.0)
    bpy.context.view_layer.update()
    frame = bake_inputs.Frame(obj)
    inputs_suns, _ = bake_inputs.gather_lights([sun], frame)
    # World -Y is the object's -X after a 90 degree turn about Z.
    assert inputs_suns[0].direction == pytest.approx((-1.0, 0.0, 0.0), abs=1e-6)
    (occluder,) = bake_inputs.gather_occluders(bake_inputs.occluder_objects(bpy.context.view_layer),
                                               bpy.context.evaluated_depsgraph_get(), frame)
    # The plane's centre (3, 0, 0) is 2 m along world +X from the object: 1 m along the object's -Y (scale 2).
    assert occluder.vertices.mean(axis=0) == pytest.approx((0.0, -1.0, 0.0), abs=1e-6)


def test_non_uniform_scale_is_refused(clean_scene, tmp_path):
    obj = volume_object(str(tmp_path / "v.vdb"))
    obj.scale = (1.0, 1.0, 2.0)
    bpy.context.view_layer.update()
    with pytest.raises(UserError, match="non-uniform"):
        bake_inputs.Frame(obj)


def test_a_snow_layer_and_its_helper_meshes_are_not_occluders(clean_scene):
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    ground = bpy.context.object
    bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.05, surface_mesh=True)
    snow = bpy.context.object
    assert len(snow.children) == 3  # the metaball points, the surface mesh and the proxy, all hidden from renders
    assert bake_inputs.occluder_objects(bpy.context.view_layer) == [ground]  # the ground under the snow stays
