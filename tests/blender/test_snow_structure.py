"""Snow's small-scale structure (issue 13) in blender -b: render modes, Nishita's sub-balls and glints, rendered
by Cycles and held against what the core says the patterns add up to (firncore.sub_ball_pattern, glint_facets,
mean_glint_radiance: closed forms checked against independent Monte Carlo in tests/cpp/structure)."""

import math

import bpy
import numpy as np
import pytest

from bake_helpers import black_world, needs_core_bake, ortho_camera, render, uniform_world
from firn.common.core import firncore
from firn.material import nodes as materials, structure
from firn.snow_layer import proxy as snow_proxy
from scene_helpers import select_only

ELEVATION = math.radians(20.0)  # camera and sun, on opposite sides: the surface's normal halves them
TOWARDS_CAMERA = (math.cos(ELEVATION), 0.0, math.sin(ELEVATION))


def flat_snow(size=1.0, depth=0.05, voxel_size=0.0):
    bpy.ops.mesh.primitive_plane_add(size=size)
    select_only(bpy.context.object)
    assert bpy.ops.firn.add_snow_layer(depth=depth, spacing=0.02, randomness=0.0, smoothness=1.0,
                                       voxel_size=voxel_size) == {"FINISHED"}
    return bpy.context.object


def add_sun(towards_sun, angle=0.0, strength=1.0):
    from mathutils import Vector

    data = bpy.data.lights.new("Sun", "SUN")
    data.energy, data.angle = strength, angle
    sun = bpy.data.objects.new("Sun", data)
    sun.rotation_euler = Vector(towards_sun).to_track_quat("Z", "Y").to_euler()  # light travels along -Z
    bpy.context.scene.collection.objects.link(sun)
    return sun


def linked_from(socket):
    assert socket.is_linked, socket.name
    return socket.links[0].from_node


def test_render_modes_build_their_materials(clean_scene):
    snow = flat_snow(size=0.4)
    proxy = snow_proxy.proxy_of(snow)
    assert snow.firn.render_mode == "BAKED" and materials.material_form(snow) == "OPTICS"
    assert linked_from(materials.snow_material(snow).node_tree.nodes["Firn Output"].inputs["Volume"]).type == \
        "PRINCIPLED_VOLUME"
    assert proxy.hide_render and not proxy.visible_camera

    snow.firn.render_mode = "SINGLE"
    nodes = materials.snow_material(snow).node_tree.nodes
    single = linked_from(nodes["Firn Output"].inputs["Volume"])
    assert single.type == "MIX_SHADER"
    assert single.inputs["Fac"].links[0].from_socket.name == "Is Camera Ray"
    assert linked_from(single.inputs[1]).type == "VOLUME_ABSORPTION"  # every other ray: extinction only
    assert linked_from(single.inputs[2]).type == "PRINCIPLED_VOLUME"  # camera rays scatter once
    assert proxy.hide_render

    snow.firn.render_mode = "OPAQUE"
    assert not materials.snow_material(snow).node_tree.nodes["Firn Output"].inputs["Volume"].is_linked
    assert not proxy.hide_render and proxy.visible_camera and proxy.visible_shadow
    surface = proxy.data.materials[0].node_tree.nodes
    assert linked_from(surface["Firn Render Mix"].inputs[1]).type == "BSDF_DIFFUSE"
    assert not surface["Firn Render Mix"].inputs["Fac"].is_linked  # no glints

    snow.firn.render_mode = "BAKED"
    snow.firn.glints = True
    assert not proxy.hide_render and proxy.visible_camera and not proxy.visible_shadow  # glints over the volume
    assert linked_from(surface["Firn Render Mix"].inputs[1]).type == "BSDF_TRANSPARENT"
    assert linked_from(surface["Firn Render Mix"].inputs["Fac"]).name == "Firn Glints"
    assert linked_from(surface["Firn Preview Shown"].inputs["Fac"]).name == "Firn Glints"  # EEVEE's preview too
    assert surface["Firn Preview Output"].target == "EEVEE" and surface["Firn Render Output"].target == "CYCLES"
    snow.firn.glints = False
    assert proxy.hide_render

    snow.firn.sub_balls = True
    nodes = materials.snow_material(snow).node_tree.nodes
    grains = linked_from(linked_from(nodes["Firn Extinction Grains"].inputs[0]).inputs[1])
    assert grains.name == "Firn Sub-Balls" and grains.node_tree.name == structure.SUB_BALL_GROUP
    assert linked_from(linked_from(grains.inputs["Depth"]).inputs[0]).attribute_name == "surface"


def _factor_image(tmp_path, depth, pattern, size=240, scale=0.12):
    """The sub-ball group's density factor on a plane `depth` m below the surface, as an emission image."""
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    plane = bpy.context.object
    material = bpy.data.materials.new("Factor")
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = structure.sub_ball_group()
    structure.set_inputs(group, {"Cells per Metre": 1.0 / pattern.cell_size, "Radius": pattern.radius,
                                 "Variation": pattern.variation, "Mean Kernel": pattern.mean_kernel,
                                 "Fade Start": pattern.fade_start, "Fade End": pattern.fade_end,
                                 "Strength": pattern.strength, "Depth": depth})
    tree.links.new(coordinates.outputs["Object"], group.inputs["Position"])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(group.outputs["Factor"], emission.inputs["Strength"])
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    plane.data.materials.append(material)
    black_world()
    ortho_camera((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), scale)
    image = render(str(tmp_path), size=(size, size), samples=4, name=f"factor_{depth}")[:, :, 0]
    bpy.data.objects.remove(plane)
    return image


def test_sub_balls_vary_at_the_grain_scale_in_the_shallow_snow_only(clean_scene, tmp_path):
    # Grains of 0.5 mm in snow of sigma_t 2000 /m fading out 3 optical depths (1.5 mm) down; cells of 1.5 mm
    # are 3 pixels here, so the image holds ~6,400 grains' cells.
    pattern = firncore.sub_ball_pattern(0.5e-3, 0.3, 3.0, 1.0, 2000.0)
    shallow = _factor_image(tmp_path, 0.0, pattern)
    # The mean density is kept: the Voronoi texture Cycles draws has the statistics the core integrated.
    assert shallow.mean() == pytest.approx(1.0, abs=0.06)
    assert np.mean(shallow < 0.05) > 0.6  # mostly gaps between grains...
    assert shallow.max() > 15.0  # ...and grain centres many times the mean
    # At the grain scale: neighbouring pixels (a third of a cell) correlate, pixels 4 cells apart do not.
    centred = shallow - shallow.mean()
    near = np.mean(centred[:, 1:] * centred[:, :-1]) / centred.var()
    far = np.mean(centred[:, 12:] * centred[:, :-12]) / centred.var()
    assert near > 0.15 and abs(far) < 0.05
    halfway = _factor_image(tmp_path, 0.75 * pattern.fade_end, pattern)
    assert halfway.mean() == pytest.approx(1.0, abs=0.06) and halfway.std() < 0.7 * shallow.std()
    deep = _factor_image(tmp_path, 1.01 * pattern.fade_end, pattern)
    assert np.abs(deep - 1.0).max() < 1e-4  # below the shallow region the density is untouched


@needs_core_bake
def test_sub_balls_keep_the_baked_slab_brightness(clean_scene, tmp_path):
    """The bake stores light per unit extinction and the sub-balls keep the mean density: switching them on
    changes a baked slab's mean brightness by less than 2 % (issue 13)."""
    uniform_world((0.4, 0.5, 0.7))
    add_sun((-0.5, 0.3, 0.8), strength=3.0)
    snow = flat_snow(size=1.0)
    assert bpy.ops.firn.bake_scattering(quality="DRAFT", seed=1) == {"FINISHED"}
    ortho_camera((0.0, 0.0, 0.05), (0.3, -0.4, 0.87), 0.3)
    plain = render(str(tmp_path), size=(48, 48), samples=32, name="plain")
    snow.firn.sub_balls = True
    assert materials.material_form(snow) == "BAKED"
    grains = render(str(tmp_path), size=(48, 48), samples=32, name="grains")
    change = grains.mean() / plain.mean() - 1.0
    assert abs(change) < 0.02, f"mean brightness changed by {change:+.2%}"


def _fresnel_towards_the_sky(eta, n=400000, seed=0):
    """Mean over facet normals (uniform on the hemisphere facing the viewer, TOWARDS_CAMERA) of F(n.v) where the
    mirrored view ray rises to the sky: Monte Carlo with Born & Wolf's Fresnel equations for unpolarised light."""
    rng = np.random.default_rng(seed)
    v = np.array(TOWARDS_CAMERA)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    mu = normals @ v
    normals[mu < 0] *= -1.0
    mu = np.abs(mu)
    mirrored = 2.0 * mu[:, None] * normals - v  # the view ray's mirror direction
    cos_t = np.sqrt(1.0 - (1.0 - mu * mu) / (eta * eta))
    r_s = (mu - eta * cos_t) / (mu + eta * cos_t)
    r_p = (eta * mu - cos_t) / (eta * mu + cos_t)
    return float(np.mean(0.5 * (r_s * r_s + r_p * r_p) * (mirrored[:, 2] > 0.0)))


SUN_ANGLE = math.radians(16.0)  # wide enough that ~100 facets in view mirror it: the counts' noise stays ~10 %
VIEW = 0.6  # m: the orthographic views' width (1.75 m of snow along the view)
PIXELS = 400  # facets of 2 mm are about a pixel across here


def _glint_scene(facets_per_m2=1.5e4, facet_radius=2e-3):
    snow = flat_snow(size=2.2, voxel_size=0.01)
    snow.firn.render_mode = "OPAQUE"  # the snow's surface alone: no volume noise under the glints
    snow.firn.glint_density, snow.firn.glint_size = facets_per_m2, facet_radius
    snow.firn.glint_roughness = 0.0  # mirrors: the expected glints are exact
    return snow


def _bright(image, reference, factor):
    """Pixels brighter than `factor` times the median of the diffuse snow (luminance of linear RGB)."""
    luminance, diffuse = image.mean(axis=2), np.median(reference.mean(axis=2))
    return luminance > factor * diffuse


def test_glints_mirror_the_sun_as_the_facets_predict(clean_scene, tmp_path):
    """Camera and sun 20 deg above the snow on opposite sides (half vector: the snow's normal, 70 deg from the
    view), sun 16 deg wide. Facets of 2 mm, 15,000 per m^2: the mean radiance they add is
    a F(70 deg) E / (8 pi cos 70 deg) whatever the sun's size; the fraction of the surface that mirrors the sun
    a Omega / (8 pi cos 70 deg) (firncore, against Monte Carlo in tests/cpp)."""
    black_world()
    add_sun((-TOWARDS_CAMERA[0], 0.0, TOWARDS_CAMERA[2]), angle=SUN_ANGLE)
    snow = _glint_scene()
    ortho_camera((0.0, 0.0, 0.05), TOWARDS_CAMERA, VIEW, distance=1.0)
    plain = render(str(tmp_path), size=(PIXELS, PIXELS), samples=16, name="plain")
    snow.firn.glints = True
    glints = render(str(tmp_path), size=(PIXELS, PIXELS), samples=16, name="glints")
    facets = firncore.glint_facets(1.5e4, 2e-3)
    cos_half = math.cos(math.pi / 2 - ELEVATION)
    added = (glints.mean(axis=2) - plain.mean(axis=2)).mean()
    # Where they mirror the sky (the material draws only those) the facets also take F(n.v) of the diffuse snow's
    # light: the material mixes by Fresnel.
    mirrored = firncore.mean_glint_radiance(facets.coverage, structure.ICE_IOR, cos_half)
    expected = mirrored - facets.coverage * _fresnel_towards_the_sky(structure.ICE_IOR) * plain.mean()
    assert added == pytest.approx(expected, rel=0.3)
    omega = math.pi * math.tan(SUN_ANGLE / 2) ** 2  # Cycles' sun: a disk of radius tan(angle / 2)
    fraction = np.mean(_bright(glints, plain, 5.0))
    expected_fraction = firncore.glint_fraction(facets.coverage, omega, cos_half)
    assert 0.3 * expected_fraction < fraction < 3.0 * expected_fraction
    assert fraction < 0.01  # a small fraction of the pixels


def test_no_glints_under_a_uniform_sky(clean_scene, tmp_path):
    uniform_world((1.0, 1.0, 1.0))
    snow = _glint_scene()
    ortho_camera((0.0, 0.0, 0.05), TOWARDS_CAMERA, VIEW, distance=1.0)
    plain = render(str(tmp_path), size=(PIXELS // 2, PIXELS // 2), samples=16, name="plain")
    snow.firn.glints = True
    glints = render(str(tmp_path), size=(PIXELS // 2, PIXELS // 2), samples=16, name="glints")
    assert not _bright(glints, plain, 2.0).any()


def test_moving_the_camera_moves_the_glints(clean_scene, tmp_path):
    """Two cameras 12 deg apart in elevation see the same stretch of snow: the sun's mirror image moves to other
    facets. Bright pixels are compared where they lie on the snow (x along the view, y across)."""
    black_world()
    add_sun((-TOWARDS_CAMERA[0], 0.0, TOWARDS_CAMERA[2]), angle=SUN_ANGLE)
    snow = _glint_scene()
    snow.firn.glints = True
    scale, size = VIEW, PIXELS

    def glint_positions(elevation, name):
        ortho_camera((0.0, 0.0, 0.05), (math.cos(elevation), 0.0, math.sin(elevation)), scale, distance=1.0)
        image = render(str(tmp_path), size=(size, size), samples=16, name=name)
        rows, columns = np.nonzero(image.mean(axis=2) > 5.0 * np.median(image.mean(axis=2)))
        pixel = scale / size
        across = (columns + 0.5 - size / 2) * pixel
        along = -((size - 1 - rows) + 0.5 - size / 2) * pixel / math.sin(elevation)  # image up = away from camera
        return np.stack([along, across], axis=1)

    first = glint_positions(ELEVATION, "first")
    again = glint_positions(ELEVATION, "again")
    moved = glint_positions(ELEVATION + math.radians(12.0), "moved")
    assert len(first) >= 5 and len(moved) >= 5

    def shared(a, b, tolerance=0.006):
        distances = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
        return np.mean(distances.min(axis=1) < tolerance)

    assert shared(first, again) == 1.0  # same camera: the same glints
    assert shared(first, moved) < 0.3
