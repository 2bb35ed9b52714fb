"""Blender objects to world-space triangle arrays for the core (numpy, metres)."""

import numpy as np

from .errors import UserError

# Object types that evaluate to a mesh (modifiers, curve bevels and NURBS tessellation applied).
MESH_LIKE_TYPES = {"MESH", "SURFACE", "CURVE", "FONT", "META"}


def check_unit_scale(scene):
    if abs(scene.unit_settings.scale_length - 1.0) > 1e-6:
        raise UserError(
            f"Firn works in metres and needs Unit Scale 1.0 (this scene has {scene.unit_settings.scale_length:g}); "
            "set it in Scene Properties > Units and scale the objects instead"
        )


def _evaluated_triangles(obj, depsgraph):
    """(vertices (N, 3) float32 world m, triangles (M, 3) uint32, material slot per triangle (M,) int32,
    materials by slot) of the evaluated object. Mirroring transforms flip the winding (faces keep pointing out)."""
    evaluated = obj.evaluated_get(depsgraph)
    materials = [slot.material for slot in evaluated.material_slots]
    mesh = evaluated.to_mesh()
    try:
        if mesh is None:
            return np.empty((0, 3), np.float32), np.empty((0, 3), np.uint32), np.empty(0, np.int32), materials
        mesh.calc_loop_triangles()
        local = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", local)
        corners = np.empty(len(mesh.loop_triangles) * 3, np.int32)
        mesh.loop_triangles.foreach_get("vertices", corners)
        slots = np.empty(len(mesh.loop_triangles), np.int32)
        mesh.loop_triangles.foreach_get("material_index", slots)
    finally:
        evaluated.to_mesh_clear()
    matrix = np.array(evaluated.matrix_world, np.float64)
    linear, translation = matrix[:3, :3], matrix[:3, 3]
    vertices = (local.reshape(-1, 3).astype(np.float64) @ linear.T + translation).astype(np.float32)
    triangles = corners.reshape(-1, 3).astype(np.uint32)
    if np.linalg.det(linear) < 0.0:
        triangles = triangles[:, ::-1].copy()
    return vertices, triangles, slots, materials


def world_triangles(obj, depsgraph):
    """(vertices (N, 3) float32 m, triangles (M, 3) uint32) of the evaluated object, in world space.

    A negative-determinant transform (mirroring) keeps faces pointing outward: their winding is flipped.
    """
    vertices, triangles, _slots, _materials = _evaluated_triangles(obj, depsgraph)
    return vertices, triangles


def world_triangles_by_material(obj, depsgraph):
    """[(vertices, triangles, material or None)]: the evaluated object's world triangles, one part per
    material slot that has faces, each with only the vertices its triangles use."""
    vertices, triangles, slots, materials = _evaluated_triangles(obj, depsgraph)
    parts = []
    for slot in np.unique(slots):
        used = triangles[slots == slot]
        kept, remapped = np.unique(used, return_inverse=True)
        material = materials[slot] if 0 <= slot < len(materials) else None
        parts.append((vertices[kept], remapped.reshape(-1, 3).astype(np.uint32), material))
    return parts


def concatenate(meshes):
    """(vertices, triangles) pairs joined into one; None when none has a triangle."""
    vertex_parts, triangle_parts, offset = [], [], 0
    for vertices, triangles in meshes:
        if len(triangles) == 0:
            continue
        vertex_parts.append(vertices)
        triangle_parts.append(triangles + np.uint32(offset))
        offset += len(vertices)
    if not triangle_parts:
        return None
    return np.concatenate(vertex_parts), np.concatenate(triangle_parts)


def merged_triangles(objects, depsgraph):
    """All objects' world triangles joined into one (vertices, triangles) pair; None when there are none."""
    return concatenate(world_triangles(obj, depsgraph) for obj in objects)


def is_mesh_like(obj):
    return obj.type in MESH_LIKE_TYPES and not obj.firn.is_snow
