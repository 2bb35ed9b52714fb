"""Snow Brush: paint snow onto the active snow layer (Nishita et al. 1997's interactive placement, as a brush).

The core's SnowCanvas holds the layer's metaballs and grids; each dab edits the balls and rasterizes again only the
leaves they reach. A stroke ends by writing the grids to a new file and the balls to the snow's metaball mesh, so
that Blender's undo (which restores the Volume's file path and the mesh) gives the snow before the stroke back, and
Rebuild from Metaballs gives the same snow. Scripts paint with a `stroke` of points, as Blender's paint operators do:

    bpy.ops.firn.snow_brush(stroke=[{"location": (x, y, z), "pressure": 1.0, ...}], mode="ADD", radius=0.3,
                            strength=0.02)

In the viewport: drag to add, Ctrl+drag to erase, Shift+drag to smooth; [ and ] change the radius; Esc or right
click ends the brush; Ctrl+Z ends it and undoes the last stroke.
"""

import math
import os
import time

import bpy
import numpy as np
from bpy_extras import view3d_utils
from mathutils import Vector

from ..common import cache, scene_geometry
from ..common.core import firncore
from ..common.errors import UserError
from ..properties import SNOW_LAYER_PROPERTIES, active_snow_layer
from . import proxy
from .operators import _max_voxels, _occluder_objects, core_settings, metaball_mesh, read_metaballs, \
    snow_with_metaballs_poll, target_triangles

MODES = (("ADD", "Add", "Add snow where the snowfall reaches, on top of the snow there"),
         ("ERASE", "Erase", "Remove snow from the top (Ctrl while painting)"),
         ("SMOOTH", "Smooth", "Even out the snow surface (Shift while painting)"))
MIN_REFRESH_INTERVAL = 0.2  # s between viewport refreshes during a stroke; more when a refresh takes long
_canvases = {}  # snow object name -> (file key, metaball count, SnowCanvas, inputs key): kept between strokes


def _file_key(path):
    """What tells a snow file apart from the one a canvas was made from or wrote: path, size, time written."""
    try:
        stat = os.stat(path)
    except OSError:
        return None
    return path, stat.st_size, stat.st_mtime_ns


def _inputs_key(snow):
    """The snow's settings and targets as the canvas saw them: a change (a new snowfall direction, another
    target) makes a new canvas."""
    settings = tuple(tuple(value) if hasattr(value, "__len__") and not isinstance(value, str) else value
                     for value in (getattr(snow.firn.layer, name) for name in SNOW_LAYER_PROPERTIES))
    return settings, tuple(item.object.name for item in snow.firn.targets if item.object is not None)


def _snow_and_canvas(context):
    """The active snow layer and its canvas, made from its file, metaballs and targets unless the one kept still
    matches them (an undo, a regeneration or a rebuild changed the file)."""
    snow = active_snow_layer(context)
    holder = snow.firn.metaballs
    path = cache.volume_path(snow.data)
    kept = _canvases.get(snow.name)
    count = len(holder.data.vertices)
    if kept is not None and kept[0] == _file_key(path) and kept[1] == count and kept[3] == _inputs_key(snow):
        return snow, kept[2]
    targets = [item.object for item in snow.firn.targets if item.object is not None]
    if not targets:
        raise UserError(f"'{snow.name}' has no target objects left to paint snow on")
    if not os.path.isfile(path):
        raise UserError(f"The snow file {path} is missing: regenerate the snow")
    metres = scene_geometry.metres_per_unit(context.scene)
    depsgraph = context.evaluated_depsgraph_get()
    target_arrays = target_triangles(targets, depsgraph)
    if target_arrays is None:
        raise UserError("The snow's targets have no faces to paint snow on")
    occluders = target_triangles(_occluder_objects(context, snow.firn.layer, targets), depsgraph)
    try:
        canvas = firncore.SnowCanvas(read_metaballs(holder, metres), core_settings(snow.firn.layer, _max_voxels(),
                                     metres), path, *target_arrays, occluders)
    except ValueError as error:
        raise UserError(f"Snow Brush: {error}") from error
    _canvases.clear()  # one canvas at a time: its grids can be large
    _canvases[snow.name] = (_file_key(path), count, canvas, _inputs_key(snow))
    return snow, canvas


def _stroke_file(snow):
    """(absolute path, stored path) of a new file for the snow after a stroke; the earlier files stay for undo."""
    for number in range(1, 100000):
        path, stored = cache.snow_file(f"{snow.name} stroke {number}")
        if not os.path.exists(path):
            return path, stored
    raise UserError("Too many snow brush files: regenerate the snow")


def _swap_mesh(obj, mesh):
    """Gives `obj` a new mesh with the old one's materials. The object itself stays: Blender 3.4 crashes on an undo
    that brings back a proxy object removed and made again (store_proxy) in a stroke."""
    old = obj.data
    for material in old.materials:
        mesh.materials.append(material)
    obj.data = mesh
    if old.users == 0:
        bpy.data.meshes.remove(old)


def _show(snow, canvas, path, stored):
    """Writes the canvas to `path` and shows it: the Volume reads it, the proxy is meshed from it."""
    cache.check_writable(path)
    cache.core_write(canvas.write, path)
    snow.data.filepath = stored
    cache.file_fixed(snow.data)
    cache.reload_grids(snow.data)
    snow.firn.mean_density = canvas.mean_density
    shown = proxy.proxy_of(snow)
    if shown is not None:
        _swap_mesh(shown, proxy.new_mesh(shown.data.name, *proxy.mesh_arrays(path, snow.firn.voxel_size),
                                          smooth=True))
        proxy.show_bake(snow)  # the new file has no bake: the proxy shows the snow's optics
    _canvases[snow.name] = (_file_key(cache.volume_path(snow.data)), *_canvases[snow.name][1:])


def _commit(snow, canvas, files):
    """A stroke's end: the grids in a new file (or the one its refreshes wrote to), the balls in the snow's
    metaball mesh."""
    metaballs = canvas.metaballs()
    _show(snow, canvas, *files)
    holder = snow.firn.metaballs
    _swap_mesh(holder, metaball_mesh(holder.data.name, metaballs))
    kept = _canvases[snow.name]
    _canvases[snow.name] = (kept[0], len(metaballs["radii"]), *kept[2:])


def _paint(canvas, points, mode, radius, strength, metres):
    """Dabs at `points` [(location Blender units, pressure)]; whether they changed any ball. UserError for what the
    core refuses."""
    if not points:
        return False
    locations = np.array([location for location, _pressure in points], np.float64) * metres
    pressures = np.array([pressure for _location, pressure in points], np.float32)
    try:
        stats = canvas.stroke(locations, pressures, mode, radius * metres, strength * metres)
    except (ValueError, firncore.BudgetError) as error:
        raise UserError(f"Snow Brush: {error}") from error
    return any(stats[key] for key in ("added", "removed", "changed"))


def _circle(centre, normal, radius, segments=48):
    """Points of a circle of `radius` around `centre` in the plane of `normal` (Blender units)."""
    normal = Vector(normal).normalized()
    t = normal.orthogonal().normalized()
    b = normal.cross(t)
    return [tuple(Vector(centre) + radius * (math.cos(a) * t + math.sin(a) * b))
            for a in (2.0 * math.pi * i / segments for i in range(segments + 1))]


def _draw_cursor(operator, _context):
    if operator.cursor is None:
        return
    import gpu
    from gpu_extras.batch import batch_for_shader

    shader = gpu.shader.from_builtin("3D_UNIFORM_COLOR")
    batch = batch_for_shader(shader, "LINE_STRIP", {"pos": _circle(*operator.cursor, operator.radius)})
    shader.bind()
    shader.uniform_float("color", (1.0, 0.55, 0.1, 1.0) if operator.painting == "ERASE" else (0.3, 0.8, 1.0, 1.0))
    gpu.state.line_width_set(2.0)
    batch.draw(shader)
    gpu.state.line_width_set(1.0)


class FIRN_OT_snow_brush(bpy.types.Operator):
    """Paint snow on the active snow layer: drag to add where the snowfall reaches, Ctrl to erase, Shift to smooth"""

    bl_idname = "firn.snow_brush"
    bl_label = "Snow Brush"
    bl_options = {"REGISTER", "UNDO"}

    stroke: bpy.props.CollectionProperty(type=bpy.types.OperatorStrokeElement, options={"SKIP_SAVE"})
    mode: bpy.props.EnumProperty(name="Mode", items=MODES, default="ADD")
    radius: bpy.props.FloatProperty(
        name="Radius", description="Brush radius, across the snowfall", subtype="DISTANCE", unit="LENGTH",
        default=0.3, min=1e-4, soft_min=0.01, soft_max=5.0)
    strength: bpy.props.FloatProperty(
        name="Strength", description="Snow depth a dab adds, removes or evens out at the brush centre",
        subtype="DISTANCE", unit="LENGTH", default=0.02, min=0.0, soft_max=0.5, precision=3)
    spacing: bpy.props.FloatProperty(
        name="Spacing", description="Distance between dabs along a stroke, as a fraction of the radius",
        subtype="FACTOR", default=0.25, min=0.02, max=2.0)

    @classmethod
    def poll(cls, context):
        if not snow_with_metaballs_poll(cls, context):
            return False
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode")
            return False
        return True

    def execute(self, context):
        """A scripted stroke: one dab per point of `stroke`, one undo step."""
        try:
            snow, canvas = _snow_and_canvas(context)
            metres = scene_geometry.metres_per_unit(context.scene)
            if _paint(canvas, [(tuple(p.location), p.pressure) for p in self.stroke], self.mode, self.radius,
                      self.strength, metres):
                _commit(snow, canvas, _stroke_file(snow))
        except UserError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}

    # --- the modal brush: strokes until Esc, each stroke pushed as its own undo step ---

    def invoke(self, context, _event):
        if context.area is None or context.area.type != "VIEW_3D":
            self.report({"ERROR"}, "Snow Brush paints in a 3D Viewport")
            return {"CANCELLED"}
        try:
            _canvases.clear()  # the scene as it is now: objects may have moved since the last brush
            _snow_and_canvas(context)  # made now, not at the first click
        except UserError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.cursor = None  # (location, normal) under the mouse, Blender units
        self.painting = None  # the stroke's mode while the button is down
        self.last_dab = None
        self.files = None
        self.changed = False  # the stroke changed a ball
        self.next_refresh = 0.0
        self.handle = bpy.types.SpaceView3D.draw_handler_add(_draw_cursor, (self, context), "WINDOW", "POST_VIEW")
        context.window_manager.modal_handler_add(self)
        context.workspace.status_text_set("Snow Brush: drag to add, Ctrl erase, Shift smooth, [ ] radius, "
                                          "Esc or right click to finish")
        return {"RUNNING_MODAL"}

    def _end(self, context, result):
        bpy.types.SpaceView3D.draw_handler_remove(self.handle, "WINDOW")
        context.workspace.status_text_set(None)
        context.area.tag_redraw()
        return result

    def _hit(self, context, event):
        """(location, normal) of the surface under the mouse (Blender units), or None."""
        region, view = context.region, context.region_data
        mouse = (event.mouse_region_x, event.mouse_region_y)
        origin = view3d_utils.region_2d_to_origin_3d(region, view, mouse)
        direction = view3d_utils.region_2d_to_vector_3d(region, view, mouse)
        hit, location, normal, _index, _obj, _matrix = context.scene.ray_cast(
            context.evaluated_depsgraph_get(), origin, direction)
        return (tuple(location), tuple(normal)) if hit else None

    def _dabs_to(self, location):
        """Points from the last dab towards `location`, `spacing` x radius apart."""
        if self.last_dab is None:
            return [location]
        start, end = Vector(self.last_dab), Vector(location)
        step = self.spacing * self.radius
        count = int((end - start).length / step)
        return [tuple(start.lerp(end, (i + 1) * step / (end - start).length)) for i in range(count)]

    def _stroke_to(self, context, location, pressure):
        snow, canvas = _snow_and_canvas(context)
        points = self._dabs_to(location)
        self.changed |= _paint(canvas, [(p, pressure) for p in points], self.painting, self.radius, self.strength,
                               scene_geometry.metres_per_unit(context.scene))
        if points:
            self.last_dab = points[-1]
        if self.changed and time.perf_counter() >= self.next_refresh:  # the volume follows the stroke, as often as it can
            started = time.perf_counter()
            if self.files is None:
                self.files = _stroke_file(snow)
            _show(snow, canvas, *self.files)
            self.next_refresh = time.perf_counter() + max(MIN_REFRESH_INTERVAL, 3.0 * (time.perf_counter() - started))

    def _finish_stroke(self, context):
        if self.changed:
            snow, canvas = _snow_and_canvas(context)
            _commit(snow, canvas, self.files or _stroke_file(snow))
            bpy.ops.ed.undo_push(message="Snow Brush")
        self.painting, self.last_dab, self.files, self.changed = None, None, None, False

    def modal(self, context, event):
        try:
            return self._modal(context, event)
        except UserError as error:
            self.report({"ERROR"}, str(error))
            return self._end(context, {"CANCELLED"})

    def _modal(self, context, event):
        context.area.tag_redraw()
        if event.type in {"ESC", "RIGHTMOUSE"} and event.value == "PRESS" and self.painting is None:
            return self._end(context, {"CANCELLED"})  # each stroke pushed its own undo step: none for the brush
        if event.type == "Z" and event.ctrl and self.painting is None:
            return self._end(context, {"CANCELLED", "PASS_THROUGH"})  # Blender's undo, on the ended brush
        if event.type in {"LEFT_BRACKET", "RIGHT_BRACKET"} and event.value == "PRESS":
            self.radius *= 1.0 / 1.15 if event.type == "LEFT_BRACKET" else 1.15
            return {"RUNNING_MODAL"}
        if event.type in {"MOUSEMOVE", "INBETWEEN_MOUSEMOVE", "LEFTMOUSE"}:
            self.cursor = self._hit(context, event)
            pressure = event.pressure if event.pressure > 0.0 else 1.0
            if event.type == "LEFTMOUSE" and event.value == "PRESS" and self.cursor is not None:
                self.painting = "ERASE" if event.ctrl else "SMOOTH" if event.shift else self.mode
                self._stroke_to(context, self.cursor[0], pressure)
            elif event.type == "LEFTMOUSE" and event.value == "RELEASE" and self.painting is not None:
                self._finish_stroke(context)
            elif self.painting is not None and self.cursor is not None:
                self._stroke_to(context, self.cursor[0], pressure)
            return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"}  # navigation and everything else


classes = (FIRN_OT_snow_brush,)
