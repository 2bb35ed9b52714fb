"""Add Snow Layer's masks: snow on the selected faces only, its depth weighted 0..1 by a vertex group or a float
point attribute (docs/user-guide.md, Masks).

Faces left out by the selection still shelter the rest (they become occluders). A target without the named vertex
group or attribute is not masked; a vertex outside an existing group has weight 0, as in Blender's modifiers.
"""

import numpy as np

from ..common import scene_geometry
from ..common.errors import UserError


def is_masked(props):
    return props.only_selected_faces or bool(props.vertex_group) or bool(props.weight_attribute)


def _selected_triangles(mesh):
    """bool per loop triangle: its face is selected."""
    selected = np.empty(len(mesh.polygons), bool)
    mesh.polygons.foreach_get("select", selected)
    polygon = np.empty(len(mesh.loop_triangles), np.int32)
    mesh.loop_triangles.foreach_get("polygon_index", polygon)
    return selected[polygon]


def _group_weights(mesh, obj, name):
    """Weight per vertex in the object's vertex group `name` (0 outside it), or None without the group."""
    index = obj.vertex_groups.find(name)
    if index < 0:
        return None
    weights = np.zeros(len(mesh.vertices), np.float32)
    for vertex in mesh.vertices:
        for element in vertex.groups:
            if element.group == index:
                weights[vertex.index] = element.weight
    return weights


def _attribute_weights(mesh, name):
    """A float point attribute per vertex, clipped to 0..1, or None without it."""
    attribute = mesh.attributes.get(name)
    if attribute is None:
        return None
    if attribute.domain != "POINT" or attribute.data_type != "FLOAT":
        raise UserError(f"Weight attribute '{name}' must be a Float attribute on points (it is "
                        f"{attribute.data_type} on {attribute.domain})")
    values = np.empty(len(mesh.vertices), np.float32)
    attribute.data.foreach_get("value", values)
    return np.clip(np.nan_to_num(values), 0.0, 1.0)


def reader(props):
    """extra(mesh, obj) for scene_geometry.evaluated_parts: (bool per loop triangle, kept or not; weight per
    vertex 0..1)."""
    def read(mesh, obj):
        keep = _selected_triangles(mesh) if props.only_selected_faces else np.ones(len(mesh.loop_triangles), bool)
        weights = np.ones(len(mesh.vertices), np.float32)
        for found in (_group_weights(mesh, obj, props.vertex_group) if props.vertex_group else None,
                      _attribute_weights(mesh, props.weight_attribute) if props.weight_attribute else None):
            if found is not None:
                weights *= found
        return keep, weights
    return read


def masked_triangles(objects, depsgraph, props):
    """((vertices, triangles) the mask keeps, weight per kept vertex, (vertices, triangles) it leaves out) of the
    evaluated objects, world m; a part is None when it has no triangle."""
    kept, left_out, weights = [], [], []
    for _name, vertices, triangles, _slots, _materials, mask in scene_geometry.evaluated_parts(
            objects, depsgraph, extra=reader(props), with_slots=False):
        if mask is None:
            continue
        keep, vertex_weights = mask
        kept.append((vertices, triangles[keep]))
        weights.append(vertex_weights)
        left_out.append((vertices, triangles[~keep]))
    joined = scene_geometry.concatenate(kept)
    if joined is None:
        return None, None, scene_geometry.concatenate(left_out)
    # concatenate skips parts without triangles: keep only the weights of the parts it joined
    weight = np.concatenate([w for w, (_v, t) in zip(weights, kept) if len(t)])
    return joined, weight, scene_geometry.concatenate(left_out)
