"""The emitters' rectangles, read from Blender's animation on the main thread before the worker starts
(docs/spray.md "Emitters"): for each selected object and each frame its centre, half side u and half side v in
world metres.

An emitter is a set of the object's vertices: its lowest face at the first frame (the face whose centre is lowest
in world space), a vertex group's vertices, or a chosen face. Their plane's axes are found once, at the first frame,
in the object's own space; at each frame the evaluated vertices (modifiers, armatures, shape keys applied) are
placed by that frame's object transform, and the rectangle is their bounding rectangle along the axes the transform
carries. Rigid motion moves the rectangle exactly; the axes never flip from one frame to the next (the core moves
each point of the rectangle linearly between frames).
"""

import numpy as np

from ..common import scene_geometry
from ..common.errors import UserError


def _local_vertices(evaluated):
    """(N, 3) float64 object-space vertices of an evaluated object's mesh, its faces' vertex lists and each
    vertex's {group index: weight}."""
    mesh = evaluated.to_mesh()
    try:
        if mesh is None:
            return np.empty((0, 3)), [], []
        points = np.empty(len(mesh.vertices) * 3, np.float64)
        mesh.vertices.foreach_get("co", points)
        faces = [tuple(polygon.vertices) for polygon in mesh.polygons]
        groups = [{g.group: g.weight for g in vertex.groups} for vertex in mesh.vertices]
    finally:
        evaluated.to_mesh_clear()
    return points.reshape(-1, 3), faces, groups


def _world(points, matrix):
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def emitter_indices(obj, evaluated, props):
    """The indices of the vertices of `obj` that throw snow (main thread, at the first frame)."""
    points, faces, groups = _local_vertices(evaluated)
    if props.emitter == "VERTEX_GROUP":
        group = obj.vertex_groups.get(props.vertex_group)
        if group is None:
            raise UserError(f"'{obj.name}' has no vertex group '{props.vertex_group}' (Emitter: Vertex Group)")
        indices = [i for i, weights in enumerate(groups) if weights.get(group.index, 0.0) > 0.0]
        where = f"vertex group '{group.name}'"
    elif not faces:
        raise UserError(f"'{obj.name}' has no faces to throw snow from: give it a face, or use a vertex group")
    elif props.emitter == "FACE":
        if props.face_index >= len(faces):
            raise UserError(f"'{obj.name}' has {len(faces)} faces: Face Index {props.face_index} is not one of them")
        indices, where = list(faces[props.face_index]), f"face {props.face_index}"
    else:
        world = _world(points, np.array(evaluated.matrix_world, np.float64))
        lowest = min(range(len(faces)), key=lambda f: world[list(faces[f]), 2].mean())
        indices, where = list(faces[lowest]), "its lowest face"
    if len(indices) < 3 or np.linalg.matrix_rank(points[indices] - points[indices].mean(0), tol=1e-9) < 2:
        raise UserError(f"'{obj.name}': {where} has no area to throw snow from")
    return indices


def plane_axes(points):
    """Two orthonormal axes (u, v) of the plane through `points` (object space): u along their longest extent."""
    _s, _singular, rows = np.linalg.svd(points - points.mean(0), full_matrices=False)
    return rows[0], rows[1]


def rectangle(world_points, u, v):
    """(3, 3): centre, half side u, half side v of the bounding rectangle of `world_points` along the world axes
    u and v (u, v orthonormal)."""
    mean = world_points.mean(0)
    along_u, along_v = (world_points - mean) @ u, (world_points - mean) @ v
    centre = mean + u * (along_u.max() + along_u.min()) / 2 + v * (along_v.max() + along_v.min()) / 2
    return np.array([centre, u * np.ptp(along_u) / 2, v * np.ptp(along_v) / 2])


def carried_axes(matrix, u_local, v_local):
    """The object-space axes u, v at a frame: carried by the transform, made orthonormal again (shear, scale)."""
    u = matrix[:3, :3] @ u_local
    u /= np.linalg.norm(u)
    normal = np.cross(u, matrix[:3, :3] @ v_local)
    normal /= np.linalg.norm(normal)
    return u, np.cross(normal, u)


def rectangles(context, objects, props, frame_start, frame_end):
    """One (F, 3, 3) float64 array per object: its emitter's rectangle at frames frame_start…frame_end, world m.
    Sets the scene's frames and puts the current frame back. UserError when an object cannot emit or does not move."""
    scene = context.scene
    metres = scene_geometry.metres_per_unit(scene)
    current = scene.frame_current, scene.frame_subframe
    try:
        scene.frame_set(frame_start)
        depsgraph = context.evaluated_depsgraph_get()
        chosen = []
        for obj in objects:
            evaluated = obj.evaluated_get(depsgraph)
            indices = emitter_indices(obj, evaluated, props)
            chosen.append((indices, *plane_axes(_local_vertices(evaluated)[0][indices])))
        frames = []
        for frame in range(frame_start, frame_end + 1):
            scene.frame_set(frame)
            depsgraph = context.evaluated_depsgraph_get()
            frames.append([_frame_rectangle(obj.evaluated_get(depsgraph), *choice, metres)
                           for obj, choice in zip(objects, chosen)])
    finally:
        scene.frame_set(current[0], subframe=current[1])
    result = [np.array([frame[i] for frame in frames]) for i in range(len(objects))]
    for obj, path in zip(objects, result):
        if np.allclose(path, path[0], rtol=0.0, atol=1e-9):
            raise UserError(f"'{obj.name}' does not move between frames {frame_start} and {frame_end}: animate it "
                            "(keyframes, a path, a parent) to throw snow")
    return result


def _frame_rectangle(evaluated, indices, u_local, v_local, metres):
    points = _local_vertices(evaluated)[0]
    if len(points) <= max(indices):
        raise UserError(f"'{evaluated.name}' changes its vertices during the animation: its emitter cannot be "
                        "followed (use a vertex group on a mesh that keeps its vertices)")
    matrix = np.array(evaluated.matrix_world, np.float64)
    u, v = carried_axes(matrix, u_local, v_local)
    return rectangle(_world(points[indices], matrix) * metres, u, v)
