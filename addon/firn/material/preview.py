"""The viewport proxy's material: snow in Solid and Material Preview (EEVEE), from the snow's optics.

Cycles renders the snow Volume; the proxy (snow_layer/proxy.py) is its surface mesh for the viewport only. Its
material shows what the optics predict of the surface: the plane albedo of a semi-infinite snowpack under
diffuse light (the white-sky albedo, per RGB) as its colour, and subsurface scattering whose radius is the
snow's transport mean free path 1 / sigma_t' (per RGB; Blender's radius is the medium's mean free path, and
the similarity-scaled, isotropic medium has sigma_t' = sigma_t (1 - g)), so edges and thin snow glow as they do
in the render. After Bake Scattering the proxy shows the bake instead: the baked source function's isotropic part
`firn_source` (W/(m² sr), vdb-contract.md), sampled at its vertices into the colour attribute BAKED_ATTRIBUTE,
emitted as the surface's radiance (what Cycles renders of optically thick snow, seen from any side). No physics
here: every number comes from firncore.
"""

import bpy

from . import optics

_TAG = "firn_preview"  # ID property marking the proxy materials Firn manages
_NODES = ("Firn Preview BSDF", "Firn Preview Output", "Firn Preview Baked", "Firn Preview Emission")
BAKED_ATTRIBUTE = "firn_baked"  # colour per proxy vertex: firn_source there
_FALLBACK_ALBEDO = (0.9, 0.9, 0.9)  # shown while the optics settings are invalid (the panel says why)


def is_preview_material(material):
    return material is not None and material.get(_TAG) == 1


def preview_values(settings, metres):
    """(colour RGB, subsurface radius RGB in Blender units) of a snow object's optics; `metres` per unit."""
    try:
        volume = optics.volume_optics(settings)
    except ValueError:
        return _FALLBACK_ALBEDO, (0.01 / metres,) * 3
    mean_free_path = volume.transport_mean_free_path(settings.mean_density)  # m per channel
    return tuple(volume.white_sky_albedo), tuple(length / metres for length in mean_free_path)


def _build(material):
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.name = bsdf.label = "Firn Preview BSDF"
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.name = output.label = "Firn Preview Output"
    output.location = (300, 0)
    tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    baked = tree.nodes.new("ShaderNodeAttribute")
    baked.name = baked.label = "Firn Preview Baked"
    baked.attribute_name = BAKED_ATTRIBUTE
    baked.location = (-300, -400)
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.name = emission.label = "Firn Preview Emission"
    emission.location = (0, -400)
    tree.links.new(baked.outputs["Color"], emission.inputs["Color"])
    bsdf.inputs["Subsurface"].default_value = 1.0
    bsdf.inputs["Specular"].default_value = 0.3  # ice's Fresnel reflectance at normal incidence is 0.018
    bsdf.inputs["Roughness"].default_value = 0.8


def ensure_preview_material(snow, mesh, metres):
    """Gives the proxy's mesh its preview material (one per snow object, reused across rebuilds) and writes the
    snow's current optics into it. Returns the material."""
    name = f"Firn Preview ({snow.name})"
    material = bpy.data.materials.get(name)
    if not is_preview_material(material):
        material = bpy.data.materials.new(name)
        material[_TAG] = 1
    mesh.materials.clear()
    mesh.materials.append(material)
    refresh_preview_material(material, snow.firn, metres)
    return material


def refresh_preview_material(material, settings, metres):
    if not all(name in (material.node_tree.nodes if material.node_tree else ()) for name in _NODES):
        _build(material)
    colour, radius = preview_values(settings, metres)
    bsdf = material.node_tree.nodes["Firn Preview BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Subsurface Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Subsurface Radius"].default_value = radius
    material.diffuse_color = (*colour, 1.0)  # Solid mode's colour
    material.roughness = 0.8


def show_baked(material, baked):
    """The preview shows the bake (emission of the baked colour attribute) or the optics (Principled)."""
    if not all(name in (material.node_tree.nodes if material.node_tree else ()) for name in _NODES):
        _build(material)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    shown = nodes["Firn Preview Emission"].outputs["Emission"] if baked else nodes["Firn Preview BSDF"].outputs["BSDF"]
    links.new(shown, nodes["Firn Preview Output"].inputs["Surface"])


def is_showing_bake(material):
    surface = material.node_tree.nodes["Firn Preview Output"].inputs["Surface"]
    return surface.is_linked and surface.links[0].from_node.name == "Firn Preview Emission"
