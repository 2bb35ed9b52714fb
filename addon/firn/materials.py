"""The snow's material: Cycles' Principled Volume driven by the density grid and the object's optics.

The unbaked material renders snow straight from its optics: sigma_t = density grid × extinction per density
into Density, the single-scattering albedo into Color and g into Anisotropy. With Absorption Color black,
Cycles' Principled Volume has extinction = Density and scattering = Density × Color, so Color is exactly the
single-scattering albedo (intern/cycles/kernel/svm/closure.h, svm_node_principled_volume). Baking replaces it
(issue "Bake Scattering").
"""

import bpy

from . import optics

_TAG = "firn_snow"  # ID property marking the materials Firn manages
_NODES = ("Firn Density", "Firn Extinction", "Firn Volume", "Firn Output")


def is_snow_material(material):
    return material is not None and material.get(_TAG) == 1


def snow_material(obj):
    """The object's Firn snow material, or None (e.g. the user gave it a material of their own)."""
    slot = _snow_slot(obj)
    return slot.material if slot else None


def ensure_snow_material(obj):
    """Gives a snow object its Firn material (created in the first slot if it has none) and returns it."""
    if _snow_slot(obj) is None:
        material = bpy.data.materials.new(f"Firn Snow ({obj.name})")
        material[_TAG] = 1
        if not obj.material_slots:
            obj.data.materials.append(None)
        slot = obj.material_slots[0]
        # Linked to the object, not its data: optics belong to the object, and linked duplicates share data.
        slot.link = "OBJECT"
        slot.material = material
    refresh_snow_material(obj)
    return snow_material(obj)


def refresh_snow_material(obj):
    """Writes the object's current optics into its Firn material; invalid settings leave it unchanged."""
    slot = _snow_slot(obj)
    if slot is None:
        return
    try:
        volume = optics.volume_optics(obj.firn)
    except ValueError:
        return  # the Snow Material panel shows why
    material = slot.material
    if material.users > 1 + int(material.use_fake_user):
        # Another object uses it too (a duplicate): its optics are this object's own from now on.
        material = material.copy()
        slot.material = material
    nodes = _nodes(material)
    nodes["Firn Extinction"].inputs[1].default_value = volume.extinction_per_density
    nodes["Firn Volume"].inputs["Color"].default_value = (*volume.albedo, 1.0)
    nodes["Firn Volume"].inputs["Anisotropy"].default_value = volume.g


def _snow_slot(obj):
    for slot in obj.material_slots:
        if is_snow_material(slot.material):
            return slot
    return None


def _nodes(material):
    """The material's Firn nodes, rebuilt if any is missing (a user edited the tree)."""
    material.use_nodes = True
    nodes = material.node_tree.nodes
    if not all(name in nodes for name in _NODES):
        _build(material.node_tree)
    return nodes


def _build(tree):
    nodes, links = tree.nodes, tree.links
    nodes.clear()

    density = nodes.new("ShaderNodeAttribute")
    density.name = "Firn Density"
    density.label = "Density (kg/m³)"
    density.attribute_type = "GEOMETRY"
    density.attribute_name = "density"
    density.location = (-600, 0)

    extinction = nodes.new("ShaderNodeMath")
    extinction.name = "Firn Extinction"
    extinction.label = "σt (1/m) = density × m²/kg"
    extinction.operation = "MULTIPLY"
    extinction.location = (-350, 0)

    volume = nodes.new("ShaderNodeVolumePrincipled")
    volume.name = "Firn Volume"
    volume.label = "Snow"
    volume.inputs["Density Attribute"].default_value = ""  # the density arrives through the link only
    volume.inputs["Absorption Color"].default_value = (0.0, 0.0, 0.0, 1.0)  # Color = single-scattering albedo
    volume.location = (-100, 0)

    output = nodes.new("ShaderNodeOutputMaterial")
    output.name = "Firn Output"
    output.location = (200, 0)

    links.new(density.outputs["Fac"], extinction.inputs[0])
    links.new(extinction.outputs["Value"], volume.inputs["Density"])
    links.new(volume.outputs["Volume"], output.inputs["Volume"])
