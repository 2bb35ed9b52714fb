"""Blender objects to world-space triangle arrays for the core (numpy, metres).

Blender units become metres here, at the seam: one Blender unit is Scene > Units > Unit Scale metres. Objects are
read through the evaluated depsgraph, so modifiers are applied and what an object instances (a collection
instance, a particle system's objects, Geometry Nodes instances) comes with it, each copy at its own place.
"""

import ctypes
import math

import numpy as np

from .errors import UserError

# Object types that evaluate to a mesh (modifiers, curve bevels and NURBS tessellation applied).
MESH_LIKE_TYPES = {"MESH", "SURFACE", "CURVE", "FONT", "META"}


def metres_per_unit(scene):
    """Metres in one Blender unit: Scene > Units > Unit Scale (0.01 in a centimetre scene)."""
    scale = scene.unit_settings.scale_length
    if not (math.isfinite(scale) and scale > 0.0):
        raise UserError(f"Scene > Units > Unit Scale must be a positive number of metres per unit (it is {scale:g})")
    return scale


def unit_matrix(scene):
    """The 4 × 4 transform from metres to Blender units: what a snow Volume (grids in metres) carries."""
    return np.diag([1.0 / metres_per_unit(scene)] * 3 + [1.0])


def _readable_in_place(evaluated, extra):
    """Whether an evaluated object's mesh can be read as it is, without to_mesh()'s copy (a quarter of the
    transfer of 1M triangles): a mesh object without modifiers (a stack may leave its last subdivision to the
    GPU, which only to_mesh() applies) and out of Edit Mode, with no mask to read."""
    return extra is None and evaluated.type == "MESH" and not evaluated.modifiers and not evaluated.data.is_editmode


def _struct_array(items, words):
    """A numpy view (len(items), words) uint32 of the C array behind a Blender collection whose items are
    `words` 32-bit words each, or None when the items do not lie one after the other at that stride."""
    count = len(items)
    if count == 0:
        return None
    first, last = items[0].as_pointer(), items[count - 1].as_pointer()
    stride = 4 * words
    if first == 0 or last - first != stride * (count - 1) or (count > 1 and items[1].as_pointer() - first != stride):
        return None
    return np.frombuffer((ctypes.c_uint32 * (words * count)).from_address(first), np.uint32).reshape(count, words)


def _loop_triangle_corners(mesh):
    """Each loop triangle's three vertex indices, flat. Blender 3.4 reads `loop_triangles.vertices` item by item
    (0.14 s per million triangles, most of the transfer): its arrays of MLoopTri (uint tri[3], poly) and MLoop
    (uint v, e) are read here in place (0.015 s), once their layout checks out against the items' own values;
    otherwise, and for other layouts, through foreach_get."""
    triangles, loops = mesh.loop_triangles, mesh.loops
    looptris, mloops = _struct_array(triangles, 4), _struct_array(loops, 2)
    if looptris is not None and mloops is not None:
        corner_loops, loop_vertices = looptris[:, :3], mloops[:, 0]
        probes = {0, len(triangles) // 2, len(triangles) - 1}
        if all(tuple(corner_loops[t]) == tuple(triangles[t].loops) for t in probes) and all(
                loop_vertices[loop] == loops[int(loop)].vertex_index for t in probes for loop in corner_loops[t]):
            try:  # numpy checks each index as it reads: a loop past the loops' array raises, nothing is read there
                return loop_vertices[corner_loops].reshape(-1)  # a copy, before the mesh can go
            except IndexError:
                pass
    corners = np.empty(len(triangles) * 3, np.int32)
    triangles.foreach_get("vertices", corners)
    return corners


def _placed(local, linear, translation):
    """(N, 3) float32 local coordinates moved by `linear` and `translation` (m), in double precision. Left as they
    are when the move is none (a ground at the origin in metres): 0.02 s less on the UI thread per 500,000
    vertices, the same values (bench/snow_layer_bench.py: byte for byte)."""
    if not translation.any() and np.array_equal(linear, np.eye(3)):
        return local
    return (local.astype(np.float64) @ linear.T + translation).astype(np.float32)


def _mesh_arrays(evaluated, matrix, metres, extra=None, with_slots=True):
    """(vertices (N, 3) float32 world m, triangles (M, 3) uint32, material slot per triangle (M,) int32,
    materials by slot) of an evaluated object placed by `matrix` (Blender units). Mirroring transforms flip the
    winding (faces keep pointing out). With `extra`, a fifth item: extra(mesh, evaluated), read from the mesh
    (loop triangles calculated; None for an object without a mesh). Without `with_slots` the slots are None:
    reading them costs a third of the transfer (Blender reads loop triangles item by item, 0.1 s per million)."""
    materials = [slot.material for slot in evaluated.material_slots]
    in_place = _readable_in_place(evaluated, extra)
    mesh = evaluated.data if in_place else evaluated.to_mesh()
    try:
        if mesh is None:
            empty = np.empty((0, 3), np.float32), np.empty((0, 3), np.uint32), np.empty(0, np.int32), materials
            return empty if extra is None else (*empty, None)
        mesh.calc_loop_triangles()
        read = () if extra is None else (extra(mesh, evaluated),)
        local = np.empty(len(mesh.vertices) * 3, np.float32)
        mesh.vertices.foreach_get("co", local)
        corners = _loop_triangle_corners(mesh)
        slots = None
        if with_slots:
            slots = np.empty(len(mesh.loop_triangles), np.int32)
            mesh.loop_triangles.foreach_get("material_index", slots)
    finally:
        if not in_place:
            evaluated.to_mesh_clear()
    linear, translation = matrix[:3, :3] * metres, matrix[:3, 3] * metres
    vertices = _placed(local.reshape(-1, 3), linear, translation)
    triangles = corners.reshape(-1, 3).astype(np.uint32, copy=False)
    if np.linalg.det(linear) < 0.0:
        triangles = triangles[:, ::-1].copy()
    return (vertices, triangles, slots, materials, *read)


def _owner(instance):
    """The original object a depsgraph entry belongs to: the instancer for an instance, else the object."""
    return (instance.parent if instance.is_instance else instance.object).original


def evaluated_parts(objects, depsgraph, extra=None, with_slots=True):
    """[(name, vertices m, triangles, slots, materials)] of everything `objects` put in the scene, evaluated:
    each object's own surface (modifiers applied) and every instance it makes, in world space, metres. With
    `extra`, each part ends with extra(mesh, evaluated object); without `with_slots` the slots are None
    (_mesh_arrays)."""
    wanted = {obj.as_pointer(): obj for obj in objects}
    metres = metres_per_unit(depsgraph.scene)
    parts, seen = [], set()
    # An instance's object is valid only during its step of the iteration: read it there.
    for instance in depsgraph.object_instances:
        obj, owner = instance.object, _owner(instance).as_pointer()
        if owner not in wanted:
            continue
        seen.add(owner)
        if obj.type not in MESH_LIKE_TYPES or not (instance.is_instance or instance.show_self):
            continue  # an Empty, or an emitter that shows only its particles
        name = f"{instance.parent.name} > {obj.name}" if instance.is_instance else obj.name
        matrix = np.array(instance.matrix_world, np.float64)
        parts.append((name, *_mesh_arrays(obj, matrix, metres, extra, with_slots)))
    # Objects the viewport hides are not in its depsgraph's list; their own surface still counts (a hidden
    # occluder collection, a ground hidden after the snow was made).
    for pointer, obj in wanted.items():
        if pointer not in seen and is_mesh_like(obj):
            evaluated = obj.evaluated_get(depsgraph)
            parts.append((obj.name, *_mesh_arrays(evaluated, np.array(evaluated.matrix_world, np.float64), metres,
                                                   extra, with_slots)))
    return parts


def world_triangles(objects, depsgraph):
    """(vertices (N, 3) float32 m, triangles (M, 3) uint32) of the evaluated objects and their instances joined
    into one, in world space; None when none has a triangle."""
    return concatenate((vertices, triangles) for _name, vertices, triangles, _slots, _materials
                       in evaluated_parts(objects, depsgraph, with_slots=False))


def world_triangles_by_material(objects, depsgraph):
    """[(name, vertices, triangles, material or None)]: the world triangles of the evaluated objects and their
    instances, one part per object or instance and material slot that has faces, each with only the vertices
    its triangles use."""
    parts = []
    for name, vertices, triangles, slots, materials in evaluated_parts(objects, depsgraph):
        for slot in np.unique(slots):
            used = triangles[slots == slot]
            kept, remapped = np.unique(used, return_inverse=True)
            material = materials[slot] if 0 <= slot < len(materials) else None
            parts.append((name, vertices[kept], remapped.reshape(-1, 3).astype(np.uint32), material))
    return parts


def concatenate(meshes):
    """(vertices, triangles) pairs joined into one; None when none has a triangle. One pair comes back as it is
    (1M triangles: copying them cost 0.06 s)."""
    parts = [(vertices, triangles) for vertices, triangles in meshes if len(triangles)]
    if len(parts) <= 1:
        return parts[0] if parts else None
    # Each part's triangles offset straight into the joined array: no temporary array per part (12 MB per
    # million triangles of fresh memory, which a first run pays for in page faults).
    joined = np.empty((sum(len(triangles) for _v, triangles in parts), 3), np.uint32)
    offset, at = 0, 0
    for vertices, triangles in parts:
        np.add(triangles, np.uint32(offset), out=joined[at:at + len(triangles)])
        offset, at = offset + len(vertices), at + len(triangles)
    return np.concatenate([vertices for vertices, _t in parts]), joined


def is_mesh_like(obj):
    """Mesh-like objects of the scene, not Firn's own: snow Volumes and their viewport proxies."""
    return obj.type in MESH_LIKE_TYPES and not (obj.firn.is_snow or obj.firn.is_proxy)


def is_instancer(obj):
    """An Empty that instances a collection (mesh-like objects bring their particle and Geometry Nodes
    instances themselves)."""
    return obj.type == "EMPTY" and obj.instance_type == "COLLECTION" and obj.instance_collection is not None


def makes_geometry(obj):
    """Objects whose evaluated surface or instances can hold or stop snow."""
    return is_mesh_like(obj) or is_instancer(obj)
