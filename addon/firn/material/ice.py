"""The ice material of grain snow: clear ice spheres, Fresnel reflection and refraction, and the ice's own
absorption. No physics here: the absorption coefficients (1/m per RGB channel) come from the core.

Surface: Mix(Refraction, Glossy) by Fresnel(η), both sharp. Cycles' Fresnel node takes 1/η on back faces, so a
ray inside a grain reflects totally beyond the critical angle (the Refraction BSDF returns nothing there).
Point clouds hold no volume in Cycles, so the ice's absorption is a tint on each refraction: a ray crosses a
sphere of radius r along a mean chord of 4r/3 (Cauchy's formula), between two refractions, so each refraction
transmits exp(-σa · 2r/3) of each channel (σa in 1/m, r in m). In visible light this is 1 - 1e-4 or closer per
grain; it matters only after the thousands of crossings light makes in deep snow.
"""

import math

import bpy

_TAG = "firn_ice"  # ID property marking the materials Firn manages


def refraction_tint(absorption_rgb, grain_radius):
    """Transmittance of one refraction, per channel: exp(-σa 2r/3), σa in 1/m, r in m (mean chord 4r/3)."""
    return tuple(math.exp(-sigma_a * 2.0 * grain_radius / 3.0) for sigma_a in absorption_rgb) + (1.0,)


def ice_material(name, ior, absorption_rgb, grain_radius):
    """A new material of clear ice spheres of mean radius `grain_radius` (m)."""
    material = bpy.data.materials.new(name)
    material[_TAG] = 1
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    fresnel = nodes.new("ShaderNodeFresnel")
    fresnel.inputs["IOR"].default_value = ior
    refraction = nodes.new("ShaderNodeBsdfRefraction")
    refraction.distribution = "SHARP"
    refraction.inputs["IOR"].default_value = ior
    refraction.inputs["Color"].default_value = refraction_tint(absorption_rgb, grain_radius)
    glossy = nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = "SHARP"
    glossy.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    mix = nodes.new("ShaderNodeMixShader")
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(fresnel.outputs["Fac"], mix.inputs["Fac"])
    links.new(refraction.outputs["BSDF"], mix.inputs[1])
    links.new(glossy.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], output.inputs["Surface"])
    for i, node in enumerate((fresnel, refraction, glossy, mix, output)):
        node.location = (200 * i - 400, 0)
    # EEVEE's material preview: refraction through the screen, so the grains read as ice there too.
    material.blend_method = "BLEND"
    material.use_screen_refraction = True
    return material
