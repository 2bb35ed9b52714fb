"""Grain snow as a Blender object: a mesh of grain centres with a `radius` point attribute (m), turned into a
point cloud by a Geometry Nodes modifier, which Cycles renders as true spheres."""

import bpy

GROUP_NAME = "Firn Grains"


def _points_group():
    """Mesh → Points, radius from the `radius` attribute, then the grains' material (a modifier input: Mesh to
    Points drops the mesh's materials). Shared by all grain objects; rebuilt if the user deleted it."""
    group = bpy.data.node_groups.get(GROUP_NAME)
    if group is not None and group.bl_idname == "GeometryNodeTree":
        return group
    group = bpy.data.node_groups.new(GROUP_NAME, "GeometryNodeTree")
    group.inputs.new("NodeSocketGeometry", "Geometry")
    group.inputs.new("NodeSocketMaterial", "Material")
    group.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = group.nodes, group.links
    source, sink = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    radius = nodes.new("GeometryNodeInputNamedAttribute")
    radius.data_type = "FLOAT"
    radius.inputs["Name"].default_value = "radius"
    to_points = nodes.new("GeometryNodeMeshToPoints")
    to_points.mode = "VERTICES"
    set_material = nodes.new("GeometryNodeSetMaterial")
    attribute = next(socket for socket in radius.outputs if socket.enabled and socket.name == "Attribute")
    links.new(source.outputs["Geometry"], to_points.inputs["Mesh"])
    links.new(attribute, to_points.inputs["Radius"])
    links.new(to_points.outputs["Points"], set_material.inputs["Geometry"])
    links.new(source.outputs["Material"], set_material.inputs["Material"])
    links.new(set_material.outputs["Geometry"], sink.inputs["Geometry"])
    for i, node in enumerate((source, radius, to_points, set_material, sink)):
        node.location = (220 * i - 330, 0)
    return group


def new_grain_object(context, name, centres, radii, material, matrix):
    """An object of one point per grain: centres (N, 3) and radii (N,) in metres, placed by `matrix` (metres →
    Blender units, as snow volumes are)."""
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(centres))
    mesh.vertices.foreach_set("co", centres.astype("float32").ravel())
    mesh.attributes.new("radius", "FLOAT", "POINT").data.foreach_set("value", radii.astype("float32"))
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    obj.matrix_world = matrix
    context.collection.objects.link(obj)
    modifier = obj.modifiers.new("Firn Grains", "NODES")
    modifier.node_group = _points_group()
    modifier[modifier.node_group.inputs["Material"].identifier] = material
    obj.firn.is_grains = True
    return obj
