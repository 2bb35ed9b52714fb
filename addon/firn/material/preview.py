"""The viewport proxy's material: snow in Solid and Material Preview (EEVEE), from the snow's optics.

Cycles renders the snow Volume; the proxy (snow_layer/proxy.py) is its surface mesh for the viewport only. Its
material shows what the optics predict of the surface: the plane albedo of a semi-infinite snowpack under
diffuse light (the white-sky albedo, per RGB) as its colour, and subsurface scattering whose radius is the
snow's transport mean free path 1 / sigma_t' (per RGB; Blender's radius is the medium's mean free path, and
the similarity-scaled, isotropic medium has sigma_t' = sigma_t (1 - g)), so edges and thin snow glow as they do
in the render. After Bake Scattering the proxy shows the bake instead: the baked source function's mean over
directions `firn_source` + `firn_source_peak` (W/(m² sr), its two lobes' means, vdb-contract.md; on a diffusely
lit surface about the radiance seen 75° from its normal, half that seen along it), sampled at its vertices into
the colour attribute BAKED_ATTRIBUTE, emitted as the surface's radiance (what Cycles renders of optically thick
snow, seen from any side). No physics here: every number comes from firncore.

The same material holds the proxy's face for Cycles (its own output, target CYCLES), used when the proxy renders
(proxy.apply_render_surface): in render mode OPAQUE a diffuse surface of the white-sky albedo, else a transparent
one over the volume; with glints, mirror facets of ice over either (material/structure.py), in EEVEE over the
preview too.
"""

import bpy

from . import optics, structure

_TAG = "firn_preview"  # ID property marking the proxy materials Firn manages
_NODES = ("Firn Preview BSDF", "Firn Preview Output", "Firn Preview Baked", "Firn Preview Emission",
          "Firn Preview Shown", "Firn Render Mix", "Firn Render Output", "Firn Render Diffuse",
          "Firn Render Transparent", "Firn Glints", "Firn Glint Glossy")
BAKED_ATTRIBUTE = "firn_baked"  # colour per proxy vertex: firn_source + firn_source_peak there
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


def _node(tree, kind, name, location):
    node = tree.nodes.new(kind)
    node.name = node.label = name
    node.location = location
    return node


def _build(material):
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    bsdf = _node(tree, "ShaderNodeBsdfPrincipled", "Firn Preview BSDF", (0, 0))
    bsdf.inputs["Subsurface"].default_value = 1.0
    bsdf.inputs["Specular"].default_value = 0.3  # ice's Fresnel reflectance at normal incidence is 0.018
    bsdf.inputs["Roughness"].default_value = 0.8
    baked = _node(tree, "ShaderNodeAttribute", "Firn Preview Baked", (-300, -400))
    baked.attribute_name = BAKED_ATTRIBUTE
    emission = _node(tree, "ShaderNodeEmission", "Firn Preview Emission", (0, -400))
    tree.links.new(baked.outputs["Color"], emission.inputs["Color"])
    # EEVEE and Solid: the preview, under the glints when they are on
    shown, glints = structure.add_glint_shader(tree, bsdf.outputs["BSDF"], (300, 0))
    shown.name = shown.label = "Firn Preview Shown"
    output = _node(tree, "ShaderNodeOutputMaterial", "Firn Preview Output", (600, 0))
    output.target = "EEVEE"
    tree.links.new(shown.outputs["Shader"], output.inputs["Surface"])
    # Cycles: the proxy's surface when it renders (proxy.apply_render_surface)
    _node(tree, "ShaderNodeBsdfDiffuse", "Firn Render Diffuse", (0, -800))
    _node(tree, "ShaderNodeBsdfTransparent", "Firn Render Transparent", (0, -1000))
    mix = _node(tree, "ShaderNodeMixShader", "Firn Render Mix", (300, -800))
    tree.links.new(shown.inputs[2].links[0].from_socket, mix.inputs[2])  # the facets' sharp Glossy
    render = _node(tree, "ShaderNodeOutputMaterial", "Firn Render Output", (600, -800))
    render.target = "CYCLES"
    tree.links.new(mix.outputs["Shader"], render.inputs["Surface"])


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


def _has_nodes(material):
    return all(name in (material.node_tree.nodes if material.node_tree else ()) for name in _NODES)


def refresh_preview_material(material, settings, metres):
    """Writes a snow object's optics (its obj.firn `settings`) and structure into its proxy's material."""
    if not _has_nodes(material):
        _build(material)
    colour, radius = preview_values(settings, metres)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Firn Preview BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Subsurface Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Subsurface Radius"].default_value = radius
    material.diffuse_color = (*colour, 1.0)  # Solid mode's colour
    material.roughness = 0.8
    nodes["Firn Render Diffuse"].inputs["Color"].default_value = (*colour, 1.0)
    base = nodes["Firn Render Diffuse" if settings.render_mode == "OPAQUE" else "Firn Render Transparent"]
    links.new(base.outputs["BSDF"], nodes["Firn Render Mix"].inputs[1])
    _show_glints(material, settings)


def _show_glints(material, settings):
    nodes, links = material.node_tree.nodes, material.node_tree.links
    glints = nodes["Firn Glints"]
    mixes = (nodes["Firn Preview Shown"], nodes["Firn Render Mix"])
    values = None
    if settings.glints:
        try:
            values = structure.glint_inputs(settings)
        except ValueError:
            pass  # the Snow Structure panel shows why
    for mix in mixes:
        for link in mix.inputs["Fac"].links:
            links.remove(link)
        mix.inputs["Fac"].default_value = 0.0
        if values is not None:
            links.new(glints.outputs["Fac"], mix.inputs["Fac"])
    if values is not None:
        structure.set_inputs(glints, values)
        nodes["Firn Glint Glossy"].inputs["Roughness"].default_value = settings.glint_roughness  # 0: mirrors


def show_baked(material, baked):
    """The preview shows the bake (emission of the baked colour attribute) or the optics (Principled)."""
    if not _has_nodes(material):
        _build(material)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    shown = nodes["Firn Preview Emission"].outputs["Emission"] if baked else nodes["Firn Preview BSDF"].outputs["BSDF"]
    links.new(shown, nodes["Firn Preview Shown"].inputs[1])


def is_showing_bake(material):
    shown = material.node_tree.nodes["Firn Preview Shown"].inputs[1]
    return shown.is_linked and shown.links[0].from_node.name == "Firn Preview Emission"
