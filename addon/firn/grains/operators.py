"""Add Grain Snow: snow as packed ice spheres on the selected objects (Chrisman), accumulated by the core."""

import math

import bpy
from mathutils import Matrix

from ..common import scene_geometry
from ..common.modes import object_mode_poll
from ..common.core import firncore
from ..common.errors import UserError
from ..common.jobs import FirnJobMixin
from ..material import ice
from ..snow_layer.operators import is_snow_target, target_triangles
from . import light_paths, points

# Lengths are metres whatever the Unit Scale (the names scripts rely on, issue 12); the redo panel shows mm.
GRAIN_SNOW_PROPERTIES = {
    "grain_radius": bpy.props.FloatProperty(
        name="Grain Radius", description="Radius of the ice spheres in metres (snow: 0.0001-0.002)",
        default=0.0005, min=1e-6, soft_min=5e-5, soft_max=0.01, precision=5, step=0.01),
    "grain_radius_variation": bpy.props.FloatProperty(
        name="Radius Variation", description="Grain radii spread uniformly over radius ± this, in metres (less than "
        "the radius)", default=0.0, min=0.0, soft_max=0.01, precision=5, step=0.01),
    "grain_count": bpy.props.IntProperty(
        name="Grains", description="How many grains fall", default=20000, min=1, soft_max=2000000),
    "ior": bpy.props.FloatProperty(
        name="Index of Refraction", description="Of ice: 1.31 (visible light)", default=1.31, min=1.0, max=3.0),
    "max_slope": bpy.props.FloatProperty(
        name="Maximum Slope", description="Grains landing on steeper surfaces roll off (are discarded)",
        subtype="ANGLE", default=math.radians(60.0), min=0.0, max=math.radians(90.0)),
    "direction": bpy.props.FloatVectorProperty(
        name="Snowfall Direction", description="The way the grains fall", subtype="DIRECTION", size=3,
        default=(0.0, 0.0, -1.0)),
    "seed": bpy.props.IntProperty(name="Seed", description="Same seed, same grains", default=0, min=0),
    "match_snow_optics": bpy.props.BoolProperty(
        name="Match Snow Optics", description="Grains on a Firn snow layer (select it as a target): give the layer "
        "the optics of these grains (Physical, their radius), so grains near the surface and volume below agree",
        default=True),
}


def gather_inputs(context, props):
    """Everything the core needs, read from Blender on the main thread; UserError for what cannot work."""
    targets = [obj for obj in context.selected_objects if is_snow_target(obj)]
    if not targets:
        raise UserError("Select the objects the grains fall on (meshes, curves, surfaces, text, metaballs, "
                        "collection instances or Firn snow)")
    if props.grain_radius_variation >= props.grain_radius:
        raise UserError(f"Radius Variation ({props.grain_radius_variation * 1e3:g} mm) must be less than the Grain "
                        f"Radius ({props.grain_radius * 1e3:g} mm)")
    if sum(abs(c) for c in props.direction) == 0.0:
        raise UserError("Snowfall Direction must not be zero")
    mesh = target_triangles(targets, context.evaluated_depsgraph_get())
    if mesh is None:
        raise UserError("The selected objects have no faces to hold grains (a curve needs a bevel or extrusion)")
    return {
        "vertices": mesh[0], "triangles": mesh[1], "targets": [obj.name for obj in targets],
        "radius": props.grain_radius, "variation": props.grain_radius_variation, "count": props.grain_count,
        "direction": tuple(props.direction), "max_slope": props.max_slope, "seed": props.seed, "ior": props.ior,
        "unit_matrix": scene_geometry.unit_matrix(context.scene),
        "snow": [obj.name for obj in targets if obj.type == "VOLUME"] if props.match_snow_optics else [],
    }


def match_snow_optics(snows, grain_radius):
    """Multi-scale snow: the volumetric layers under the grains take the grains' optics (Physical, their radius:
    KZ04 matches a pile of ice spheres, docs/grains.md). Returns the report's note ("" when none)."""
    for snow in snows:
        snow.firn.optics_mode = "PHYSICAL"
        snow.firn.grain_radius = grain_radius
    names = ", ".join(snow.name for snow in snows)
    return f"; {names} now has the grains' optics (bake it again if it was baked)" if snows else ""


def compute_grains(inputs, progress):
    """Worker thread: the core accumulates the grains; no bpy here."""
    centres, radii, stats = firncore.accumulate_grains(
        inputs["vertices"], inputs["triangles"], count=inputs["count"], radius=inputs["radius"],
        radius_variation=inputs["variation"] / inputs["radius"], direction=inputs["direction"],
        max_slope_deg=math.degrees(inputs["max_slope"]), seed=inputs["seed"], progress=progress)
    return dict(stats, centres=centres, radii=radii)


class FIRN_OT_add_grain_snow(FirnJobMixin, bpy.types.Operator):
    """Cover the selected objects with snow made of ice grains, rendered as true spheres (slow, exact close-ups)"""

    bl_idname = "firn.add_grain_snow"
    bl_label = "Add Grain Snow"
    bl_options = {"REGISTER", "UNDO"}
    __annotations__ = dict(GRAIN_SNOW_PROPERTIES)
    job_label = "Add Grain Snow"

    poll = classmethod(object_mode_poll)

    def draw(self, _context):
        col = self.layout.column()
        col.use_property_split = True
        col.use_property_decorate = False
        for name in GRAIN_SNOW_PROPERTIES:
            col.prop(self, name)
            if name in ("grain_radius", "grain_radius_variation"):
                col.label(text=f"{getattr(self, name) * 1e3:.3f} mm")

    def prepare(self, context):
        return gather_inputs(context, self)

    compute = staticmethod(compute_grains)

    def apply(self, context, inputs, result):
        centres, radii = result["centres"], result["radii"]
        if len(radii) == 0:
            raise UserError("No grain landed: the selected surfaces are all steeper than the Maximum Slope")
        material = ice.ice_material("Firn Ice", inputs["ior"], firncore.ice_absorption_rgb(inputs["radius"]),
                                    inputs["radius"])
        obj = points.new_grain_object(context, "Grain Snow", centres, radii, material,
                                      Matrix(inputs["unit_matrix"].tolist()))
        for other in context.selected_objects:
            other.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
        matched = match_snow_optics([bpy.data.objects[name] for name in inputs["snow"]], inputs["radius"])
        changes = light_paths.raise_light_paths(context.scene)
        self.report({"INFO"}, summary(inputs, result) + matched +
                    (f"; Cycles light paths raised: {', '.join(changes)}" if changes else ""))


def summary(inputs, result):
    """What landed where, and what did not, for the operator's report."""
    count = len(result["radii"])
    short = f" (of {inputs['count']:,}: the rays ran out)" if count < inputs["count"] else ""
    steep = f", {result['steep']:,} steep landings discarded" if result["steep"] else ""
    return f"{count:,} grains{short} on {', '.join(inputs['targets'])}{steep}"


def _menu_entry(self, _context):
    self.layout.operator(FIRN_OT_add_grain_snow.bl_idname, icon="PARTICLE_POINT")


classes = (FIRN_OT_add_grain_snow,)


def register_extras():
    bpy.types.VIEW3D_MT_add.append(_menu_entry)


def unregister_extras():
    bpy.types.VIEW3D_MT_add.remove(_menu_entry)
