"""The baked snow material: its nodes, and what Cycles renders from baked grids (docs/vdb-contract.md) - the
snow's own look from several directions and the light it throws on a neighbouring surface. The grids are
written here with known constant values, so these tests need no core bake."""

import math

import bpy
import numpy as np
import pytest

from bake_helpers import (K, RHO, S, S_X, S_Y, S_Z, baked_slab, black_world, mean_pixel, ortho_camera, render,
                          uniform_source, write_volume)
from firn.bake import operators as bake, state as bake_state
from firn.material import nodes as materials

def linked_from(socket):
    assert socket.is_linked, socket.name
    return socket.links[0].from_node


def test_baked_material_nodes(clean_scene, tmp_path):
    obj = baked_slab(str(tmp_path), uniform_source(S, S_X, S_Y, S_Z))
    material = materials.snow_material(obj)
    assert materials.is_baked_material(material) and obj.material_slots[0].link == "OBJECT"
    nodes = material.node_tree.nodes
    output = nodes["Firn Output"]
    assert not output.inputs["Surface"].is_linked
    shader = linked_from(output.inputs["Volume"])
    assert shader.type == "ADD_SHADER"
    absorption, emission = linked_from(shader.inputs[0]), linked_from(shader.inputs[1])
    assert (absorption.type, emission.type) == ("VOLUME_ABSORPTION", "EMISSION")
    # Volume Absorption absorbs (1 - Color) x Density: black Color, Density = sigma_t = k x density.
    assert tuple(absorption.inputs["Color"].default_value)[:3] == (0.0, 0.0, 0.0)
    extinction = linked_from(absorption.inputs["Density"])
    assert extinction.operation == "MULTIPLY" and extinction.inputs[1].default_value == pytest.approx(K)
    assert linked_from(extinction.inputs[0]).attribute_name == "density"
    assert linked_from(emission.inputs["Strength"]) == extinction
    # Color = S(w), the contract's two lobes: fed by the six grids and by Incoming turned into the object's frame.
    assert linked_from(emission.inputs["Color"]) == nodes["Firn Lobes"]
    grids = {node.attribute_name for node in nodes if node.type == "ATTRIBUTE"} - {"density"}
    assert grids == set(materials.BAKED_GRIDS)
    unit = nodes["Firn Incoming Object"]
    assert (unit.vector_type, unit.convert_from, unit.convert_to) == ("VECTOR", "WORLD", "OBJECT")
    assert unit.inputs["Vector"].links[0].from_socket.name == "Incoming"


def lobe(l0, l1, w):
    """The contract's source function (docs/vdb-contract.md), per channel: l0 (1 - k²) / (1 + k² - 2 k cos)^1.5,
    k = min(|l1| / (3 l0), 0.95), cos = w . l1 / |l1|; l1 given as the x, y, z grids' RGB values."""
    l0, l1 = np.array(l0, float), np.array(l1, float).T  # l1: one row per channel
    length = np.linalg.norm(l1, axis=1)
    k = np.minimum(np.divide(length, 3 * l0, out=np.zeros(3), where=l0 > 0), 0.95)
    cos = np.divide(l1 @ np.array(w, float), length, out=np.zeros(3), where=length > 0)
    return l0 * (1 - k * k) / (1 + k * k - 2 * k * cos) ** 1.5


def peak(p0, p1, w):
    """The contract's peaked lobe: p0 (1 - k²) / (1 + k² - 2 k cos)^1.5 per channel, one k = min(|p1| / (3 mean(p0)),
    0.95) and cos = w . p1 / |p1| for all channels."""
    p0, p1 = np.array(p0, float), np.array(p1, float)
    length, mean = np.linalg.norm(p1), p0.mean()
    k = min(length / (3 * mean), 0.95) if mean > 0 else 0.0
    cos = p1 @ np.array(w, float) / length if length > 0 else 0.0
    return p0 * (1 - k * k) / (1 + k * k - 2 * k * cos) ** 1.5


def source_function(source, w):
    """Both lobes of the grids' values in BAKED_GRIDS' order (the peaked one absent: zero)."""
    source = tuple(source) + ((0.0, 0.0, 0.0),) * (6 - len(source))
    return lobe(source[0], source[1:4], w) + peak(source[4], source[5], w)


# A peaked source: green's lobe is clamped at k = 0.95, blue has none, red is moderate.
PEAKED = ((0.2, 0.1, 0.4), (0.3, 0.0, 0.0), (0.1, 0.5, 0.0), (0.2, 0.5, 0.0))
# Both lobes: the broad one above, and a peaked one of k 0.62 along (0.53, 0.27, -0.80).
TWO_LOBES = PEAKED + ((0.3, 0.2, 0.1), (0.2, 0.1, -0.3))


@pytest.mark.parametrize("towards_camera", [(0.0, 0.0, 1.0),
                                            (math.sin(math.radians(60)), 0.0, math.cos(math.radians(60))),
                                            (0.0, -math.sin(math.radians(45)), math.cos(math.radians(45)))])
@pytest.mark.parametrize("source", [(S, S_X, S_Y, S_Z), PEAKED, TWO_LOBES])
def test_snow_renders_its_source_function(clean_scene, tmp_path, towards_camera, source):
    """A thick slab of an absorbing, emitting medium renders exactly the lobes S(w) of its grids, w towards the
    camera, with Cycles' default settings (step rate 1, volume bounces 0): 30 optical depths per step. The
    core's renderer evaluates the same lobes (lobeRadiance, peakRadiance, tests/cpp/transport/source_lobe_test.cpp); a real bake
    rendered both ways: test_bake_end_to_end.py."""
    black_world()
    baked_slab(str(tmp_path), uniform_source(*source))
    ortho_camera((0, 0, 0), towards_camera, scale=0.05)
    expected = source_function(source, towards_camera)
    assert mean_pixel(render(str(tmp_path), size=(8, 8))) == pytest.approx(expected, rel=2e-3)  # measured 1e-6


def test_direction_is_taken_in_the_volume_frame(clean_scene, tmp_path):
    """A volume turned 90 degrees about Z: the grids' x axis is world +Y, so w = (sin 60, 0, cos 60) in the
    world is (0, -sin 60, cos 60) for the grids."""
    black_world()
    baked_slab(str(tmp_path), uniform_source(S, S_X, S_Y, S_Z), rotation=(0.0, 0.0, math.radians(90)))
    theta = math.radians(60)
    ortho_camera((0, 0, 0), (math.sin(theta), 0.0, math.cos(theta)), scale=0.05)
    expected = lobe(S, (S_X, S_Y, S_Z), (0.0, -math.sin(theta), math.cos(theta)))
    assert mean_pixel(render(str(tmp_path), size=(8, 8))) == pytest.approx(expected, rel=2e-3)  # measured 1e-6


def parallel_rectangle_view_factor(a, b, c):
    """Differential area to a parallel a x b rectangle with one corner straight above it at height c
    (Howell, A Catalog of Radiation Heat Transfer Configuration Factors, B-3)."""
    x, y = a / c, b / c
    return (x / math.sqrt(1 + x * x) * math.atan(y / math.sqrt(1 + x * x))
            + y / math.sqrt(1 + y * y) * math.atan(x / math.sqrt(1 + y * y))) / (2 * math.pi)


def test_snow_lights_a_neighbouring_surface(clean_scene, tmp_path):
    """Bounce light: a ceiling of baked snow above a white diffuse floor, nothing else lit. The floor under its
    centre receives E = pi S F (F the view factor to the ceiling's underside) and shows L = albedo E / pi.
    Gating the emission to camera rays only would leave the floor black."""
    black_world()
    voxel, half, height = 0.025, 40, 0.25  # a 2 m x 2 m ceiling 25 cm above the floor
    source = (0.5, 1.0, 1.5)
    baked_slab(str(tmp_path), uniform_source(source), voxel=voxel, half=half, depth=3,
               z_top=round(height / voxel) + 2)
    bpy.ops.mesh.primitive_plane_add(size=6.0)
    floor = bpy.context.object
    albedo = 0.8
    material = bpy.data.materials.new("Floor")
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (albedo, albedo, albedo, 1.0)
    tree.links.new(diffuse.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    floor.data.materials.append(material)
    ortho_camera((0, 0, 0), (0, 0, 1), scale=0.04, distance=0.1)
    # The density ramp puts the ceiling's underside half a voxel below its lowest voxel centre.
    underside = (round(height / voxel) - 0.5) * voxel
    view_factor = 4 * parallel_rectangle_view_factor(half * voxel, half * voxel, underside)
    expected = albedo * view_factor * np.array(source)
    # 16k paths: 0.3 % noise (measured 0.4 % off)
    assert mean_pixel(render(str(tmp_path), size=(8, 8), samples=256)) == pytest.approx(expected, rel=0.02)


def test_optics_changes_leave_the_bake_as_it_was(clean_scene, tmp_path):
    obj = baked_slab(str(tmp_path), uniform_source(S))
    obj.firn.extinction_per_density = 2 * K
    obj.firn.anisotropy = 0.5
    nodes = materials.snow_material(obj).node_tree.nodes
    assert materials.is_baked_material(materials.snow_material(obj))
    assert nodes["Firn Extinction"].inputs[1].default_value == pytest.approx(K)


def test_file_without_baked_grids_gets_the_optics_material(clean_scene, tmp_path):
    """A regenerated snow file has no baked grids: its material goes back to the optics, whatever was baked."""
    obj = baked_slab(str(tmp_path), uniform_source(S))
    write_volume(bake_state.snow_path(obj), 0.01, (0, 0, 0), (3, 3, 3), RHO)
    obj.data.grids.unload()
    obj.data.grids.load()
    material = materials.ensure_snow_material(obj)
    assert not materials.is_baked_material(material)
    assert material.node_tree.nodes["Firn Volume"].type == "PRINCIPLED_VOLUME"
    assert material.node_tree.nodes["Firn Extinction"].inputs[1].default_value == pytest.approx(K)


def test_bake_needs_full_precision_and_no_clipping_and_says_so(clean_scene, tmp_path):
    obj = baked_slab(str(tmp_path), uniform_source(S))
    assert bake._render_settings(obj) == []  # Firn's own volumes already have them
    obj.data.render.precision = "HALF"
    obj.data.render.clipping = 0.001
    changed = bake._render_settings(obj)
    assert changed == ["'Snow' volume precision Half → Full", "'Snow' volume clipping 0.001 → 0"]
    assert obj.data.render.precision == "FULL" and obj.data.render.clipping == 0.0
