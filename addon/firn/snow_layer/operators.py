"""Add Snow Layer: snow on the selected objects, as a Volume object of OpenVDB grids made by the core.

Selected snow objects are targets too: a new layer lies on their surface (layers stack).
"""

import math
import os

import bpy
import numpy as np
from mathutils import Matrix, Vector

from ..common import cache, placement, preferences, scene_geometry
from ..common.modes import no_job_poll, object_mode_poll
from ..common.core import firncore
from ..common.errors import UserError
from ..common.jobs import FirnJobMixin
from ..material import nodes as materials
from ..properties import SNOW_LAYER_PROPERTIES, active_snow_layer, is_spray
from . import masks, proxy
from .ui import draw_layer_settings

LENGTH_SETTINGS = ("depth", "spacing")  # with a non-zero default, in Blender units (voxel size 0 is automatic)


def copy_settings(source, target):
    for name in SNOW_LAYER_PROPERTIES:
        setattr(target, name, getattr(source, name))


def core_settings(props, max_voxels, metres):
    """firncore.SnowLayerSettings from any holder of SNOW_LAYER_PROPERTIES. Its lengths are Blender units (what
    the user types and sees, shown in the scene's units), `metres` per unit: the core gets metres."""
    return firncore.SnowLayerSettings(
        depth=props.depth * metres, max_slope=props.max_slope, spacing=props.spacing * metres,
        randomness=props.randomness, smoothness=props.smoothness, direction=tuple(props.direction),
        spread=props.spread, compaction=props.compaction, density_top=props.density_top,
        density_bottom=props.density_bottom, seed=props.seed, voxel_size=props.voxel_size * metres,
        max_voxels=max_voxels)


def _max_voxels():
    prefs = preferences.get()
    return prefs.voxel_budget_millions * 1e6 if prefs else 50e6


def is_snow_target(obj):
    """Objects snow can lie on: anything that evaluates to a mesh, collection instances, and earlier snow
    (layers stack)."""
    return scene_geometry.makes_geometry(obj) or (obj.type == "VOLUME" and obj.firn.is_snow)


def target_triangles(objects, depsgraph):
    """World triangles (m) of mesh-like objects with their instances, and of the surface of snow objects (their
    grids are in world metres already: vdb-contract.md)."""
    meshes = [scene_geometry.world_triangles([obj for obj in objects if obj.type != "VOLUME"], depsgraph)]
    return scene_geometry.concatenate(mesh for mesh in meshes + _snow_surfaces(objects) if mesh is not None)


def _snow_surfaces(objects):
    meshes = []
    for obj in objects:
        path = bpy.path.abspath(obj.data.filepath) if obj.type == "VOLUME" else ""
        if os.path.exists(path):
            meshes.append(firncore.snow_surface_mesh(path))
    return meshes


def masked_target_triangles(objects, depsgraph, props):
    """(targets (vertices, triangles), weight per target vertex, faces the mask leaves out) in world m; earlier
    snow is never masked."""
    kept, weights, left_out = masks.masked_triangles([obj for obj in objects if obj.type != "VOLUME"], depsgraph,
                                                     props)
    surfaces = [mesh for mesh in _snow_surfaces(objects) if len(mesh[1])]
    parts = ([kept] if kept is not None else []) + surfaces
    if not parts:
        return None, None, left_out
    weights = np.concatenate(([weights] if kept is not None else []) +
                             [np.ones(len(vertices), np.float32) for vertices, _t in surfaces])
    return scene_geometry.concatenate(parts), weights, left_out


def _occluder_objects(context, props, targets):
    if props.occluders == "COLLECTION":
        collection = bpy.data.collections.get(props.occluder_collection)
        if collection is None:
            raise UserError(f"Occluder collection '{props.occluder_collection}' does not exist")
        candidates = collection.all_objects
    else:
        candidates = [obj for obj in context.view_layer.objects if obj.visible_get()]
    # Earlier snow shelters nothing: a second layer on the same objects overlaps the first; to stack a layer on
    # earlier snow, select the snow as a target.
    return [obj for obj in candidates if scene_geometry.makes_geometry(obj) and obj not in targets]


def gather_inputs(context, props, targets, object_name, level_of_detail):
    """Everything the core needs, read from Blender on the main thread; `level_of_detail` (OFF, ON, AUTOMATIC)
    says whether the camera's footprint is read."""
    metres = scene_geometry.metres_per_unit(context.scene)
    if not targets:
        raise UserError("Select the objects to cover with snow (meshes, curves, surfaces, text, metaballs, "
                        "collection instances or earlier snow)")
    depsgraph = context.evaluated_depsgraph_get()
    weights, left_out = None, None
    if masks.is_masked(props):
        target_arrays, weights, left_out = masked_target_triangles(targets, depsgraph, props)
    else:
        target_arrays = target_triangles(targets, depsgraph)
    if target_arrays is None:
        raise UserError("The selected objects have no faces to hold snow (a curve needs a bevel or extrusion"
                        f"{'; Selected Faces Only needs faces selected in Edit Mode' if left_out else ''})")
    occluders = target_triangles(_occluder_objects(context, props, targets), depsgraph)
    occluders = scene_geometry.concatenate(mesh for mesh in (occluders, left_out) if mesh is not None)
    path, stored_path = cache.snow_file(object_name)
    cache.check_writable(path)
    settings = core_settings(props, _max_voxels(), metres)
    try:
        settings.validate()
    except ValueError as error:
        raise UserError(f"Add Snow Layer: {error}") from error
    band_path, band_stored = cache.snow_file(f"{object_name} LOD")
    return {
        "targets": target_arrays, "weights": weights, "occluders": occluders, "settings": settings, "path": path,
        "stored_path": stored_path, "surface_mesh": props.surface_mesh,
        "unit_matrix": scene_geometry.unit_matrix(context.scene),
        "level_of_detail": level_of_detail,
        "camera": camera_footprint(context.scene, depsgraph, metres, level_of_detail),
        "band_pattern": band_path[:-len(".vdb")] + "_{level}.vdb",
        "band_stored_pattern": band_stored[:-len(".vdb")] + "_{level}.vdb",
    }


def camera_footprint(scene, depsgraph, metres, mode):
    """firncore.CameraFootprint of the scene camera as evaluated now (world m), or None: levels of detail off, or
    automatic in a scene without a perspective camera."""
    if mode == "OFF":
        return None
    camera = scene.camera
    if camera is None or camera.type != "CAMERA" or camera.data.type != "PERSP":
        if mode == "ON":
            raise UserError("Level of Detail sizes voxels by the scene camera's pixels: set a perspective camera "
                            "as the scene's camera (Scene Properties > Camera), or turn Level of Detail off")
        return None
    render, data = scene.render, camera.data
    scale = render.resolution_percentage / 100.0
    width, height = render.resolution_x * scale, render.resolution_y * scale
    # The lens's angle spans the sensor's fitted side (Auto: the longer side of the image).
    fit = data.sensor_fit if data.sensor_fit != "AUTO" else ("HORIZONTAL" if width >= height else "VERTICAL")
    angle, pixels, other = ((data.angle_x, width, height) if fit == "HORIZONTAL" else (data.angle_y, height, width))
    if data.sensor_fit == "AUTO":
        angle = data.angle
    half = math.tan(0.5 * angle)
    diagonal = math.atan(half * math.hypot(1.0, other / pixels))  # the view's corners, half-angle
    matrix = camera.evaluated_get(depsgraph).matrix_world
    forward = (matrix.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
    return firncore.CameraFootprint(
        position=tuple(matrix.translation * metres), forward=tuple(forward), pixel_angle=angle / pixels,
        view_half_angle=diagonal + 0.1 + math.hypot(data.shift_x, data.shift_y) * angle)


def compute_snow(inputs, progress):
    """Worker thread: the core generates the grids and writes the VDB; no bpy here. Levels of detail when asked
    for, or when automatic and one voxel size is over the budget (the core refuses at once when it surely is)."""
    vertices, triangles = inputs["targets"]
    camera = inputs.get("camera")
    if camera is not None and inputs["level_of_detail"] == "ON":
        return compute_bands(inputs, progress)
    try:
        settings = inputs["settings"]
        result = cache.core_write(firncore.generate_snow_layer, vertices, triangles, inputs["occluders"], settings,
                                  inputs["path"], progress, inputs["weights"],
                                  proxy.mesh_settings(settings.effective_voxel_size))
    except firncore.BudgetError as error:
        if camera is None:
            raise
        return dict(compute_bands(inputs, progress), uniform_refusal=str(error))
    return with_meshes(inputs, result)


def compute_bands(inputs, progress):
    """Worker thread: snow with levels of detail, one VDB per band, and each band's viewport proxy."""
    vertices, triangles = inputs["targets"]
    result = cache.core_write(firncore.generate_snow_bands, vertices, triangles, inputs["occluders"],
                              inputs["settings"], inputs["camera"], inputs["band_pattern"], progress,
                              inputs["weights"])
    for band in result["bands"]:
        far = is_far_surface(band["voxel_size"], inputs["settings"].depth)
        band["proxy"] = (proxy.far_surface_arrays if far else proxy.mesh_arrays)(band["path"], band["voxel_size"])
    return result


def with_meshes(inputs, result):
    """Worker thread: the viewport proxy's mesh (unless the core made it with the file), and the full surface mesh
    when asked for, from the new file."""
    if "proxy" not in result:
        result["proxy"] = proxy.mesh_arrays(inputs["path"], result["voxel_size"])
    if inputs["surface_mesh"]:
        result["surface"] = firncore.snow_surface_mesh(inputs["path"])
    return result


def input_notes(result):
    """What the core did to the input geometry, for the operator's report: "" when nothing."""
    notes = []
    if result.get("dropped_triangles"):
        notes.append(f"{result['dropped_triangles']} degenerate faces skipped")
    if result.get("open_surfaces_turned"):
        notes.append(f"normals ignored on {result['open_surfaces_turned']} open surface(s) facing down: snow falls "
                     "on their upper side")
    return "".join(f"; {note}" for note in notes)


def metaball_mesh(name, metaballs):
    """The metaballs as a point mesh: centres as vertices (m, in the snow's space), the rest as attributes."""
    mesh = bpy.data.meshes.new(name)
    centres = metaballs["centres"]
    mesh.vertices.add(len(centres))
    mesh.vertices.foreach_set("co", centres.ravel())
    for key in ("radii", "bases", "depths"):
        mesh.attributes.new(key, "FLOAT", "POINT").data.foreach_set("value", metaballs[key])
    mesh.attributes.new("normals", "FLOAT_VECTOR", "POINT").data.foreach_set("vector", metaballs["normals"].ravel())
    return mesh


def _store_metaballs(snow, metaballs):
    """The metaballs as a point mesh child of the snow (hidden): edit it, then Rebuild from Metaballs."""
    name = f"{snow.name} Metaballs"
    holder = bpy.data.objects.new(name, metaball_mesh(name, metaballs))
    holder.parent = snow
    holder.hide_viewport = holder.hide_render = True
    for collection in snow.users_collection:
        collection.objects.link(holder)
    snow.firn.metaballs = holder


def _metaball_matrix(holder, metres):
    """The point mesh's coordinates → world metres. Its parent is the snow, whose space is world metres: the
    transform relative to it, read from the object itself (right even before the depsgraph updates matrix_world)."""
    if holder.parent is not None and holder.parent.firn.is_snow:
        return np.array(holder.matrix_parent_inverse @ holder.matrix_basis, np.float64)
    return np.array(holder.matrix_world, np.float64) * metres


def read_metaballs(holder, metres):
    """The metaball arrays back from the point mesh (after the user edited it), in world metres."""
    mesh = holder.data
    n = len(mesh.vertices)
    centres = np.empty(n * 3, np.float32)
    mesh.vertices.foreach_get("co", centres)
    matrix = _metaball_matrix(holder, metres)
    centres = (centres.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]).astype(np.float32)
    arrays = {"centres": centres}
    for key in ("radii", "bases", "depths"):
        if key not in mesh.attributes:
            raise UserError(f"'{holder.name}' lost its '{key}' attribute: regenerate the snow")
        values = np.empty(n, np.float32)
        mesh.attributes[key].data.foreach_get("value", values)
        arrays[key] = values
    normals = np.empty(n * 3, np.float32)
    mesh.attributes["normals"].data.foreach_get("vector", normals)
    arrays["normals"] = normals.reshape(-1, 3)
    return arrays


def _store_surface_mesh(snow, surface):
    mesh = proxy.new_mesh(f"{snow.name} Surface", *surface)
    surface_object = bpy.data.objects.new(mesh.name, mesh)
    placement.follow(surface_object, snow)  # metres in the snow's space; it stays put if the snow is deleted
    surface_object.hide_render = True  # the volume renders the snow; the mesh is for the viewport and modelling
    for collection in snow.users_collection:
        collection.objects.link(surface_object)


def _remove_children(snow):
    """The metaballs, surface mesh and proxy; a spray's objects (children too, spray/operators.py) stay."""
    for child in list(snow.children):
        if is_spray(child):
            continue
        data = child.data
        bpy.data.objects.remove(child)
        if data is not None and data.users == 0:
            bpy.data.meshes.remove(data)


def write_snow(snow, inputs, result):
    """Points the snow Volume at its new file and refreshes everything derived from it. The grids are in world
    metres; the object's transform turns them into Blender units (vdb-contract.md), and its children (metaballs,
    surface mesh, in metres too) follow it."""
    snow.matrix_world = Matrix(inputs["unit_matrix"].tolist())
    volume = snow.data
    volume.filepath = inputs["stored_path"]
    cache.file_fixed(volume)
    cache.reload_grids(volume)
    snow.firn.mean_density = result["mean_density"]
    snow.firn.voxel_size = result["voxel_size"]
    _remove_children(snow)
    _store_metaballs(snow, result["metaballs"])
    if "surface" in result:
        _store_surface_mesh(snow, result["surface"])
    materials.ensure_snow_material(snow)
    if "proxy" in result:
        proxy.store_proxy(snow, result["proxy"], 1.0 / inputs["unit_matrix"][0, 0])


# A band whose voxels are coarser than this fraction of the depth cannot hold the layer's light transport (fewer
# than two voxels through it); a pixel there sees only the snow's albedo: it renders as a surface.
FAR_SURFACE_DEPTH_FRACTION = 0.5


def is_far_surface(voxel_size, depth):
    """Whether a band of `voxel_size` m renders as a surface for snow `depth` m deep."""
    return voxel_size > FAR_SURFACE_DEPTH_FRACTION * depth


def write_bands(context, inputs, result):
    """One snow object per band: the finest takes the layer's name, the others "<name> LOD <level>". Each is a
    snow layer of its own (material, bake, proxy); the metaballs are not kept (millions over a valley: the
    brush and Rebuild work on layers without levels of detail). Far bands render as their proxy's surface (render
    mode Opaque: the white-sky albedo of the same optics, the plane albedo a deep snowpack's volume has under a
    uniform sky), and Cycles loads none of their grids."""
    objects = []
    depth = inputs["settings"].depth  # m
    density = result["bands"][0]["mean_density"]  # the snow's, measured where voxels are finest
    for band in result["bands"]:
        name = inputs["name"] if not objects else f"{inputs['name']} LOD {band['level']}"
        snow = new_snow_object(context, name)
        snow.matrix_world = Matrix(inputs["unit_matrix"].tolist())
        snow.data.filepath = inputs["band_stored_pattern"].replace("{level}", str(band["level"]))
        cache.file_fixed(snow.data)
        cache.reload_grids(snow.data)
        snow.firn.mean_density = density
        snow.firn.voxel_size = band["voxel_size"]
        snow.firn.lod_level = band["level"]
        materials.ensure_snow_material(snow)
        proxy.store_proxy(snow, band["proxy"], 1.0 / inputs["unit_matrix"][0, 0])
        if is_far_surface(band["voxel_size"], depth):
            snow.firn.render_mode = "OPAQUE"  # its update rebuilds the material and renders the proxy
        objects.append(snow)
    return objects


def band_summary(result, depth):
    """The operator's report for snow with levels of detail."""
    voxels = sum(band["active_voxels"] for band in result["bands"])
    sizes = ", ".join(f"{band['voxel_size'] * 1000:.0f}" for band in result["bands"])
    reason = " (one voxel size is over the budget)" if "uniform_refusal" in result else ""
    surfaces = sum(is_far_surface(band["voxel_size"], depth) for band in result["bands"])
    far = f", the farthest {surfaces} as surfaces" if surfaces else ""
    return (f"Snow with levels of detail{reason}: {len(result['bands'])} bands of {sizes} mm voxels{far}, "
            f"{voxels:,} voxels{input_notes(result)}")


def new_snow_object(context, name):
    volume = bpy.data.volumes.new(name)
    volume.render.precision = "FULL"  # half floats cut thin snow (cycles-volumes notes)
    volume.render.clipping = 0.0
    volume.display.density = 0.02
    snow = bpy.data.objects.new(name, volume)
    context.collection.objects.link(snow)
    snow.firn.is_snow = True
    return snow


def free_object_name(base):
    if base not in bpy.data.objects:
        return base
    for i in range(1, 10000):
        name = f"{base}.{i:03d}"
        if name not in bpy.data.objects:
            return name
    raise UserError("Too many objects named Snow")


def snow_with_metaballs_poll(operator, context):
    """Poll of the operators that work on a snow layer's kept metaballs (Rebuild, the Snow Brush)."""
    snow = active_snow_layer(context)
    if snow is None or snow.firn.metaballs is None:
        operator.poll_message_set("Select a snow object made by Add Snow Layer (that kept its metaballs)")
        return False
    return no_job_poll(operator)  # it rewrites the layer's file, which a running job may read


class FIRN_OT_add_snow_layer(FirnJobMixin, bpy.types.Operator):
    """Cover the selected objects with a layer of snow where falling snow lands"""

    bl_idname = "firn.add_snow_layer"
    bl_label = "Add Snow Layer"
    bl_options = {"REGISTER", "UNDO"}
    __annotations__ = dict(SNOW_LAYER_PROPERTIES)
    job_label = "Add Snow Layer"

    @classmethod
    def poll(cls, context):
        # From Edit Mode the selected faces can be the mask; the operator returns to Object Mode.
        return context.mode == "EDIT_MESH" or object_mode_poll(cls, context)

    def draw(self, _context):
        draw_layer_settings(self.layout, self)

    def physical_defaults(self, metres):
        """Lengths left at their defaults mean the defaults in metres (10 cm of snow) in any Unit Scale, not
        1 mm of snow in a centimetre scene."""
        for name in LENGTH_SETTINGS:
            if not self.properties.is_property_set(name):
                setattr(self, name, self.properties.bl_rna.properties[name].default / metres)

    def prepare(self, context):
        self.physical_defaults(scene_geometry.metres_per_unit(context.scene))
        if context.mode == "EDIT_MESH":
            if not self.properties.is_property_set("only_selected_faces"):
                self.only_selected_faces = True
            bpy.ops.object.mode_set(mode="OBJECT")  # writes the edit meshes (and their selection) back
        targets = [obj for obj in context.selected_objects if is_snow_target(obj)]
        name = free_object_name("Snow")
        return dict(gather_inputs(context, self, targets, name, self.level_of_detail), name=name,
                    targets_objects=targets)

    compute = staticmethod(compute_snow)

    def apply(self, context, inputs, result):
        if "bands" in result:
            layers = write_bands(context, inputs, result)
            report = band_summary(result, inputs["settings"].depth)
        else:
            layers = [new_snow_object(context, inputs["name"])]
            write_snow(layers[0], inputs, result)
            report = (f"Snow on {len(inputs['targets_objects'])} objects: {result['active_voxels']:,} voxels of "
                      f"{result['voxel_size'] * 1000:.1f} mm{input_notes(result)}")
        for snow in layers:
            copy_settings(self, snow.firn.layer)
            for obj in inputs["targets_objects"]:
                snow.firn.targets.add().object = obj
        for obj in context.selected_objects:
            obj.select_set(False)
        for snow in layers:  # left selected: what Bake Scattering bakes next (surface bands need no bake)
            snow.select_set(snow.firn.render_mode != "OPAQUE")
        context.view_layer.objects.active = layers[0]
        self.report({"INFO"}, report)


class FIRN_OT_regenerate_snow(FirnJobMixin, bpy.types.Operator):
    """Rebuild the active snow from its targets and settings, after the scene changed"""

    bl_idname = "firn.regenerate_snow"
    bl_label = "Regenerate Snow"
    bl_options = {"REGISTER", "UNDO"}
    job_label = "Regenerate Snow"

    @classmethod
    def poll(cls, context):
        if active_snow_layer(context) is None:
            cls.poll_message_set("Select a snow object made by Add Snow Layer")
            return False
        return no_job_poll(cls)  # it rewrites the layer's file, which a running job may read

    def prepare(self, context):
        snow = active_snow_layer(context)
        if snow.firn.lod_level >= 0:
            raise UserError(f"'{snow.name}' is one band of snow with levels of detail: delete its bands and use "
                            "Add Snow Layer again (bands are made together)")
        targets = [item.object for item in snow.firn.targets if item.object is not None]
        if not targets:
            kept = " or Rebuild from Metaballs" if snow.firn.metaballs is not None else ""
            raise UserError(f"'{snow.name}' has no target objects left: use Add Snow Layer{kept} instead")
        # One voxel size: a layer made with levels of detail is refused above.
        return dict(gather_inputs(context, snow.firn.layer, targets, snow.name, "OFF"), name=snow.name)

    compute = staticmethod(compute_snow)

    def apply(self, context, inputs, result):
        write_snow(bpy.data.objects[inputs["name"]], inputs, result)
        notes = input_notes(result)
        if notes:
            self.report({"INFO"}, f"Snow regenerated{notes}")


class FIRN_OT_rebuild_from_metaballs(FirnJobMixin, bpy.types.Operator):
    """Rebuild the snow volume from its (edited) metaballs"""

    bl_idname = "firn.rebuild_from_metaballs"
    bl_label = "Rebuild from Metaballs"
    bl_options = {"REGISTER", "UNDO"}
    job_label = "Rebuild from Metaballs"

    @classmethod
    def poll(cls, context):
        return snow_with_metaballs_poll(cls, context)

    def prepare(self, context):
        snow = active_snow_layer(context)
        metres = scene_geometry.metres_per_unit(context.scene)
        settings = core_settings(snow.firn.layer, _max_voxels(), metres)
        path, stored_path = cache.snow_file(snow.name)
        cache.check_writable(path)
        return {"name": snow.name, "metaballs": read_metaballs(snow.firn.metaballs, metres), "settings": settings,
                "path": path, "stored_path": stored_path, "surface_mesh": snow.firn.layer.surface_mesh,
                "unit_matrix": scene_geometry.unit_matrix(context.scene)}

    @staticmethod
    def compute(inputs, progress):
        settings = inputs["settings"]
        result = cache.core_write(firncore.rasterize_metaballs, inputs["metaballs"], settings, inputs["path"],
                                  progress, proxy.mesh_settings(settings.effective_voxel_size))
        return with_meshes(inputs, result)

    def apply(self, context, inputs, result):
        write_snow(bpy.data.objects[inputs["name"]], inputs, result)


def _menu_entry(self, _context):
    self.layout.operator(FIRN_OT_add_snow_layer.bl_idname, icon="FREEZE")


classes = (FIRN_OT_add_snow_layer, FIRN_OT_regenerate_snow,
           FIRN_OT_rebuild_from_metaballs)


def register_extras():
    bpy.types.VIEW3D_MT_add.append(_menu_entry)
    bpy.types.VIEW3D_MT_object.append(_menu_entry)


def unregister_extras():
    bpy.types.VIEW3D_MT_add.remove(_menu_entry)
    bpy.types.VIEW3D_MT_object.remove(_menu_entry)
