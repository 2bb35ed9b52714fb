"""Grain snow as a Blender object: a mesh of grain centres with a `radius` point attribute (m), turned by a
Geometry Nodes modifier into ice spheres.

For the render, each grain is an instance of one smooth icosphere scaled by its radius. Cycles 3.4's own point
primitives would be cheaper, but light cannot cross them: a ray refracted into a point sphere does not meet the
sphere again on its way out (Cycles skips the primitive a ray leaves from), so it crosses one interface instead
of two (measured: 2 % transmission loss instead of the 4 % of two ice interfaces at normal incidence). In the
viewport the grains are points (fast to draw); the points carry the same radius.
"""

import bpy

GROUP_NAME = "Firn Grains"
SPHERE_SUBDIVISIONS = 3  # 1,280 triangles: the smooth normals are within 0.3 % of the true sphere's


def _points_group():
    """Grains → instanced ice spheres for the render, points in the viewport. Shared by all grain objects (the
    material is a modifier input); rebuilt if the user deleted it."""
    group = bpy.data.node_groups.get(GROUP_NAME)
    if group is not None and group.bl_idname == "GeometryNodeTree":
        return group
    group = bpy.data.node_groups.new(GROUP_NAME, "GeometryNodeTree")
    group.inputs.new("NodeSocketGeometry", "Geometry")
    group.inputs.new("NodeSocketMaterial", "Material")
    group.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = group.nodes, group.links
    new = nodes.new
    source, sink = new("NodeGroupInput"), new("NodeGroupOutput")
    radius = new("GeometryNodeInputNamedAttribute")
    radius.data_type = "FLOAT"
    radius.inputs["Name"].default_value = "radius"
    radius_out = next(socket for socket in radius.outputs if socket.enabled and socket.name == "Attribute")
    # Render: one smooth unit icosphere of ice, instanced at every grain, scaled by its radius.
    sphere = new("GeometryNodeMeshIcoSphere")
    sphere.inputs["Radius"].default_value = 1.0
    sphere.inputs["Subdivisions"].default_value = SPHERE_SUBDIVISIONS
    smooth, ice = new("GeometryNodeSetShadeSmooth"), new("GeometryNodeSetMaterial")
    instances = new("GeometryNodeInstanceOnPoints")
    links.new(sphere.outputs["Mesh"], smooth.inputs["Geometry"])
    links.new(smooth.outputs["Geometry"], ice.inputs["Geometry"])
    links.new(source.outputs["Material"], ice.inputs["Material"])
    links.new(source.outputs["Geometry"], instances.inputs["Points"])
    links.new(ice.outputs["Geometry"], instances.inputs["Instance"])
    links.new(radius_out, instances.inputs["Scale"])
    # Viewport: points of the same radius.
    to_points, points_ice = new("GeometryNodeMeshToPoints"), new("GeometryNodeSetMaterial")
    to_points.mode = "VERTICES"
    links.new(source.outputs["Geometry"], to_points.inputs["Mesh"])
    links.new(radius_out, to_points.inputs["Radius"])
    links.new(to_points.outputs["Points"], points_ice.inputs["Geometry"])
    links.new(source.outputs["Material"], points_ice.inputs["Material"])
    switch = new("GeometryNodeSwitch")
    switch.input_type = "GEOMETRY"
    links.new(new("GeometryNodeIsViewport").outputs["Is Viewport"], switch.inputs["Switch"])
    geometry_inputs = [socket for socket in switch.inputs if socket.type == "GEOMETRY"]
    links.new(instances.outputs["Instances"], geometry_inputs[0])  # False: the render
    links.new(points_ice.outputs["Geometry"], geometry_inputs[1])  # True: the viewport
    geometry_outputs = [socket for socket in switch.outputs if socket.type == "GEOMETRY"]
    links.new(geometry_outputs[0], sink.inputs["Geometry"])
    return group


def new_grain_object(context, name, centres, radii, material, matrix):
    """An object of one vertex per grain: centres (N, 3) and radii (N,) in metres, placed by `matrix` (metres →
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
