"""Panels: they only draw; operators act."""

import bpy


class FIRN_PT_sidebar(bpy.types.Panel):
    bl_label = "Firn"
    bl_idname = "FIRN_PT_sidebar"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Firn"

    def draw(self, context):
        layout = self.layout
        obj = context.object
        if obj is not None and obj.firn.is_snow:
            layout.label(text=f"Snow: {obj.name}", icon="FREEZE")
        else:
            layout.label(text="Select objects to cover with snow")


classes = (FIRN_PT_sidebar,)
