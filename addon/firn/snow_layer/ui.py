"""Add Snow Layer's panels: the Firn sidebar tab and the snow object's settings. Panels only draw."""

import bpy

from ..common.panels import draw_file_problem
from ..properties import SNOW_LAYER_PROPERTIES, active_snow, active_snow_layer, is_spray


def draw_layer_settings(layout, holder):
    """Add Snow Layer's settings, of the operator (redo panel) or kept on a snow object."""
    col = layout.column()
    col.use_property_split = True
    col.use_property_decorate = False
    for name in SNOW_LAYER_PROPERTIES:
        if name == "occluder_collection":
            if holder.occluders == "COLLECTION":
                col.prop_search(holder, name, bpy.data, "collections")
        else:
            col.prop(holder, name)


def draw_snow_layer(layout, snow):
    """The snow's generation settings and what can be done with them."""
    draw_file_problem(layout, snow.data)
    layout.row().prop(snow.firn, "display", expand=True)
    draw_layer_settings(layout, snow.firn.layer)
    targets = ", ".join(item.object.name for item in snow.firn.targets if item.object) or "none"
    layout.label(text=f"Targets: {targets}")
    layout.label(text=f"Mean density {snow.firn.mean_density:.0f} kg/m³, voxels {snow.firn.voxel_size * 1000:.1f} mm")
    row = layout.row(align=True)
    row.operator("firn.regenerate_snow", icon="FILE_REFRESH")
    row.operator("firn.rebuild_from_metaballs", icon="META_BALL")
    layout.operator("firn.snow_brush", icon="BRUSH_DATA")


class FIRN_PT_sidebar(bpy.types.Panel):
    bl_label = "Firn"
    bl_idname = "FIRN_PT_sidebar"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Firn"

    def draw(self, context):
        layout = self.layout
        layout.operator("firn.add_snow_layer", icon="FREEZE")
        layout.operator("firn.add_grain_snow", icon="PARTICLE_POINT")
        snow = active_snow(context)
        if snow is None:
            layout.label(text="Select objects, then Add Snow Layer")
            return
        layout.label(text=snow.name, icon="VOLUME_DATA")
        if not is_spray(snow):  # a spray's own panel (Firn Snow Spray), a Lit Volume's Firn Bake, says what it is
            draw_snow_layer(layout, snow)


class FIRN_PT_object_snow_layer(bpy.types.Panel):
    bl_label = "Firn Snow Layer"
    bl_idname = "FIRN_PT_object_snow_layer"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return active_snow_layer(context) is not None

    def draw(self, context):
        draw_snow_layer(self.layout, active_snow_layer(context))


classes = (FIRN_PT_sidebar, FIRN_PT_object_snow_layer)
