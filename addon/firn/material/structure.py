"""Snow's small-scale structure as shader node groups: Nishita's sub-balls and glint facets (docs/structure.md).

Both draw from one solid texture with no memory: Cycles' Voronoi texture (3-D, F1, randomness 1) puts one random
point in every lattice cell, and the cell's random Color gives each its size or orientation. The core says what
the pattern adds up to (firncore.sub_ball_pattern, firncore.glint_facets), so the groups only evaluate it:
  Firn Sub-Balls: density factor 1 + strength w(depth) (K / mean K - 1), K = (1 - (d/R)^2)^3 of the nearest grain;
  Firn Glints: a mirror facet of ice where the surface cuts a cell's ball, its normal uniform over the sphere
  (turned towards the viewer: the facets are thin plates), weighted by ice's Fresnel reflectance; drawn only
  where it mirrors the view above the surface (below, it would mirror snow as bright as its surroundings).
"""

import functools
import math

import bpy

from ..common.core import firncore

SUB_BALL_GROUP = "Firn Sub-Balls"
GLINT_GROUP = "Firn Glints"
ICE_IOR = 1.31  # the facets' Fresnel reflectance (Warren & Brandt 2008: 1.31 across the visible)
_TAG = "firn_structure"  # ID property: the version of a Firn-built group
_VERSION = 2


def _group(name, build):
    group = bpy.data.node_groups.get(name)
    if group is None or group.get(_TAG) != _VERSION:
        if group is None:
            group = bpy.data.node_groups.new(name, "ShaderNodeTree")
        group.nodes.clear()
        group.inputs.clear()
        group.outputs.clear()
        build(group)
        group[_TAG] = _VERSION
    return group


def _math(group, operation, a, b=None, c=None, label=""):
    node = group.nodes.new("ShaderNodeMath")
    node.operation, node.label = operation, label
    for index, value in enumerate((a, b, c)):
        if value is None:
            continue
        if isinstance(value, (int, float)):
            node.inputs[index].default_value = value
        else:
            group.links.new(value, node.inputs[index])
    return node.outputs[0]


def _voronoi(group, position, scale):
    voronoi = group.nodes.new("ShaderNodeTexVoronoi")
    voronoi.voronoi_dimensions, voronoi.feature, voronoi.distance = "3D", "F1", "EUCLIDEAN"
    voronoi.inputs["Randomness"].default_value = 1.0
    group.links.new(position, voronoi.inputs["Vector"])
    group.links.new(scale, voronoi.inputs["Scale"])
    channels = group.nodes.new("ShaderNodeSeparateColor")
    group.links.new(voronoi.outputs["Color"], channels.inputs["Color"])
    return voronoi.outputs["Distance"], channels.outputs


def _build_sub_balls(group):
    for name, kind in (("Position", "NodeSocketVector"), ("Depth", "NodeSocketFloat"),
                       ("Cells per Metre", "NodeSocketFloat"), ("Radius", "NodeSocketFloat"),
                       ("Variation", "NodeSocketFloat"), ("Mean Kernel", "NodeSocketFloat"),
                       ("Fade Start", "NodeSocketFloat"), ("Fade End", "NodeSocketFloat"),
                       ("Strength", "NodeSocketFloat")):
        group.inputs.new(kind, name)
    group.outputs.new("NodeSocketFloat", "Factor")
    inputs = group.nodes.new("NodeGroupInput").outputs
    distance, channels = _voronoi(group, inputs["Position"], inputs["Cells per Metre"])
    # R = Radius (1 + Variation (2u - 1)), u the cell's red channel
    spread = _math(group, "MULTIPLY", _math(group, "MULTIPLY_ADD", channels[0], 2.0, -1.0), inputs["Variation"])
    radius = _math(group, "MULTIPLY", _math(group, "ADD", spread, 1.0), inputs["Radius"], label="R (cells)")
    ratio = _math(group, "DIVIDE", distance, radius)
    q = _math(group, "MAXIMUM", _math(group, "SUBTRACT", 1.0, _math(group, "MULTIPLY", ratio, ratio)), 0.0)
    kernel = _math(group, "POWER", q, 3.0, label="K = (1 - (d/R)²)³")
    excess = _math(group, "SUBTRACT", _math(group, "DIVIDE", kernel, inputs["Mean Kernel"]), 1.0)
    fade = group.nodes.new("ShaderNodeMapRange")
    fade.label, fade.clamp = "w(depth)", True
    group.links.new(inputs["Depth"], fade.inputs["Value"])
    group.links.new(inputs["Fade Start"], fade.inputs["From Min"])
    group.links.new(inputs["Fade End"], fade.inputs["From Max"])
    fade.inputs["To Min"].default_value, fade.inputs["To Max"].default_value = 1.0, 0.0
    weight = _math(group, "MULTIPLY", fade.outputs["Result"], inputs["Strength"])
    factor = _math(group, "MULTIPLY_ADD", excess, weight, 1.0, label="1 + s w (K / mean K - 1)")
    group.links.new(factor, group.nodes.new("NodeGroupOutput").inputs["Factor"])


def _build_glints(group):
    for name, kind in (("Position", "NodeSocketVector"), ("Cells per Metre", "NodeSocketFloat"),
                       ("Radius", "NodeSocketFloat")):
        group.inputs.new(kind, name)
    group.outputs.new("NodeSocketFloat", "Fac")
    group.outputs.new("NodeSocketVector", "Normal")
    inputs = group.nodes.new("NodeGroupInput").outputs
    distance, channels = _voronoi(group, inputs["Position"], inputs["Cells per Metre"])
    inside = _math(group, "LESS_THAN", distance, inputs["Radius"], label="on a facet")
    # n uniform over the sphere: z = 2u - 1, phi = 2 pi v, n = (sqrt(1 - z²) cos phi, sqrt(1 - z²) sin phi, z)
    z = _math(group, "MULTIPLY_ADD", channels[0], 2.0, -1.0)
    phi = _math(group, "MULTIPLY", channels[1], 2.0 * math.pi)
    ring = _math(group, "SQRT", _math(group, "SUBTRACT", 1.0, _math(group, "MULTIPLY", z, z)))
    normal = group.nodes.new("ShaderNodeCombineXYZ")
    group.links.new(_math(group, "MULTIPLY", ring, _math(group, "COSINE", phi)), normal.inputs["X"])
    group.links.new(_math(group, "MULTIPLY", ring, _math(group, "SINE", phi)), normal.inputs["Y"])
    group.links.new(z, normal.inputs["Z"])
    world = group.nodes.new("ShaderNodeVectorTransform")
    world.vector_type, world.convert_from, world.convert_to = "NORMAL", "OBJECT", "WORLD"
    group.links.new(normal.outputs["Vector"], world.inputs["Vector"])
    # A thin plate reflects on both sides: turn n towards the viewer (Incoming points at it).
    incoming = group.nodes.new("ShaderNodeNewGeometry").outputs["Incoming"]
    dot = group.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    group.links.new(world.outputs["Vector"], dot.inputs[0])
    group.links.new(incoming, dot.inputs[1])
    facing = group.nodes.new("ShaderNodeVectorMath")
    facing.operation = "SCALE"
    group.links.new(world.outputs["Vector"], facing.inputs[0])
    group.links.new(_math(group, "SIGN", dot.outputs["Value"]), facing.inputs["Scale"])
    fresnel = group.nodes.new("ShaderNodeFresnel")
    fresnel.inputs["IOR"].default_value = ICE_IOR
    group.links.new(facing.outputs["Vector"], fresnel.inputs["Normal"])
    # A facet whose mirror image of the view points into the snow shows the snow there, about as bright as the
    # snow around it: only facets mirroring the sky (and the sun) are drawn.
    towards = group.nodes.new("ShaderNodeVectorMath")
    towards.operation = "SCALE"
    towards.inputs["Scale"].default_value = -1.0
    group.links.new(incoming, towards.inputs[0])
    mirrored = group.nodes.new("ShaderNodeVectorMath")
    mirrored.operation = "REFLECT"
    group.links.new(towards.outputs["Vector"], mirrored.inputs[0])
    group.links.new(facing.outputs["Vector"], mirrored.inputs[1])
    rising = group.nodes.new("ShaderNodeVectorMath")
    rising.operation = "DOT_PRODUCT"
    group.links.new(mirrored.outputs["Vector"], rising.inputs[0])
    group.links.new(group.nodes.new("ShaderNodeNewGeometry").outputs["Normal"], rising.inputs[1])
    sky_facet = _math(group, "MULTIPLY", inside, _math(group, "GREATER_THAN", rising.outputs["Value"], 0.0))
    out = group.nodes.new("NodeGroupOutput").inputs
    group.links.new(_math(group, "MULTIPLY", sky_facet, fresnel.outputs["Fac"], label="facet × Fresnel"), out["Fac"])
    group.links.new(facing.outputs["Vector"], out["Normal"])


def sub_ball_group():
    return _group(SUB_BALL_GROUP, _build_sub_balls)


def glint_group():
    return _group(GLINT_GROUP, _build_glints)


# The core's patterns integrate a Monte Carlo (tens of ms): the panel asks on every redraw, the material on every
# optics change, for the same few settings.
_sub_ball_pattern = functools.lru_cache(maxsize=64)(firncore.sub_ball_pattern)
_glint_facets = functools.lru_cache(maxsize=64)(firncore.glint_facets)


def sub_ball_inputs(settings, sigma_t):
    """Group input values of a snow object's sub-balls (obj.firn) in snow of extinction sigma_t (1/m).
    ValueError when the settings are out of range."""
    pattern = _sub_ball_pattern(settings.sub_ball_radius, settings.sub_ball_variation, settings.sub_ball_depth,
                                settings.sub_ball_strength, sigma_t)
    return {"Cells per Metre": 1.0 / pattern.cell_size, "Radius": pattern.radius, "Variation": pattern.variation,
            "Mean Kernel": pattern.mean_kernel, "Fade Start": pattern.fade_start, "Fade End": pattern.fade_end,
            "Strength": pattern.strength}


def glint_inputs(settings):
    """Group input values of a snow object's glints (obj.firn); ValueError when out of range."""
    facets = _glint_facets(settings.glint_density, settings.glint_size)
    return {"Cells per Metre": 1.0 / facets.cell_size, "Radius": facets.radius}


def set_inputs(node, values):
    for name, value in values.items():
        node.inputs[name].default_value = value


def add_glint_shader(tree, base, location):
    """Mix(base, Glossy along the facet normal, facet × Fresnel) in `tree`; returns (mix, glint group node). The
    Glossy ('Firn Glint Glossy', GGX) takes the facets' roughness; the group node's Position is the object's
    coordinates (metres for Firn snow and its proxy)."""
    nodes, links = tree.nodes, tree.links
    x, y = location
    coordinates = nodes.new("ShaderNodeTexCoord")
    coordinates.location = (x - 600, y - 200)
    glints = nodes.new("ShaderNodeGroup")
    glints.node_tree = glint_group()
    glints.name = glints.label = "Firn Glints"
    glints.location = (x - 400, y - 200)
    links.new(coordinates.outputs["Object"], glints.inputs["Position"])
    glossy = nodes.new("ShaderNodeBsdfGlossy")
    glossy.name = glossy.label = "Firn Glint Glossy"
    glossy.distribution = "GGX"
    glossy.location = (x - 200, y - 300)
    links.new(glints.outputs["Normal"], glossy.inputs["Normal"])
    mix = nodes.new("ShaderNodeMixShader")
    mix.location = (x, y)
    links.new(glints.outputs["Fac"], mix.inputs["Fac"])
    links.new(base, mix.inputs[1])
    links.new(glossy.outputs["BSDF"], mix.inputs[2])
    return mix, glints
