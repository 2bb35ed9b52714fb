"""Panel helpers shared by every feature's panels (panels only draw; operators act)."""

import bpy


def panel_pair(name, label, poll, draw):
    """Two panels that draw the same: FIRN_PT_<name> in Properties > Object, and FIRN_PT_sidebar_<name> under
    the Firn tab of the 3D viewport's sidebar. `poll(context)` -> bool, `draw(layout, obj)`."""
    members = {
        "bl_label": label,
        "poll": classmethod(lambda cls, context: poll(context)),
        "draw": lambda self, context: draw(self.layout, context.object),
    }
    in_properties = type(f"FIRN_PT_{name}", (bpy.types.Panel,), dict(
        members, bl_idname=f"FIRN_PT_{name}", bl_space_type="PROPERTIES", bl_region_type="WINDOW",
        bl_context="object"))
    in_sidebar = type(f"FIRN_PT_sidebar_{name}", (bpy.types.Panel,), dict(
        members, bl_idname=f"FIRN_PT_sidebar_{name}", bl_space_type="VIEW_3D", bl_region_type="UI",
        bl_category="Firn", bl_parent_id="FIRN_PT_sidebar"))
    return in_properties, in_sidebar
