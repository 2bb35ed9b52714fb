"""Panels: they only draw; operators act."""

import bpy


def _active_snow(context):
    obj = context.active_object
    return obj if obj is not None and obj.type == "VOLUME" and obj.firn.is_snow else None


def draw_snow_layer(layout, snow):
    """The snow's generation settings and what can be done with them."""
    layer = snow.firn.layer
    col = layout.column()
    col.use_property_split = True
    col.use_property_decorate = False
    for name in ("depth", "max_slope", "spacing", "randomness", "smoothness", "direction", "spread",
                 "compaction", "density_top", "density_bottom", "seed", "voxel_size", "occluders"):
        col.prop(layer, name)
    if layer.occluders == "COLLECTION":
        col.prop_search(layer, "occluder_collection", bpy.data, "collections")
    col.prop(layer, "surface_mesh")
    targets = ", ".join(item.object.name for item in snow.firn.targets if item.object) or "none"
    layout.label(text=f"Targets: {targets}")
    layout.label(text=f"Mean density {snow.firn.mean_density:.0f} kg/m³, voxels {snow.firn.voxel_size * 1000:.1f} mm")
    row = layout.row(align=True)
    row.operator("firn.regenerate_snow", icon="FILE_REFRESH")
    row.operator("firn.rebuild_from_metaballs", icon="META_BALL")


class FIRN_PT_sidebar(bpy.types.Panel):
    bl_label = "Firn"
    bl_idname = "FIRN_PT_sidebar"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Firn"

    def draw(self, context):
        layout = self.layout
        layout.operator("firn.add_snow_layer", icon="FREEZE")
        snow = _active_snow(context)
        if snow is None:
            layout.label(text="Select objects, then Add Snow Layer")
            return
        layout.label(text=snow.name, icon="VOLUME_DATA")
        draw_snow_layer(layout, snow)


class FIRN_PT_object_snow_layer(bpy.types.Panel):
    bl_label = "Firn Snow Layer"
    bl_idname = "FIRN_PT_object_snow_layer"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return _active_snow(context) is not None

    def draw(self, context):
        draw_snow_layer(self.layout, _active_snow(context))


classes = (FIRN_PT_sidebar, FIRN_PT_object_snow_layer)
