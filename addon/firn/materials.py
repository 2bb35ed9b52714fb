"""The snow material: Cycles volume shading of a snow object's density grid."""

import bpy


def ensure_snow_material(obj):
    """Gives a snow object its volume material (created once, then kept)."""
    name = f"{obj.name} Snow"
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    volume = tree.nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Density Attribute"].default_value = "density"
    # Placeholder optics until the snow-material optics land: fresh snow, r = 100 um, sigma_t per kg/m^3.
    volume.inputs["Density"].default_value = 16.4
    volume.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    volume.inputs["Anisotropy"].default_value = 0.85
    tree.links.new(volume.outputs["Volume"], output.inputs["Volume"])
    if not obj.data.materials:
        obj.data.materials.append(material)
    else:
        obj.data.materials[0] = material
    return material
