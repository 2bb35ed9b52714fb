"""Panel helpers shared by every feature's panels (panels only draw; operators act)."""

import bpy

from . import cache


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


def draw_file_problem(layout, volume):
    """A red line when a snow Volume's file is missing or damaged, and what to do about it."""
    problem = cache.file_problem(volume)
    if problem is None:
        return
    col = layout.column(align=True)
    col.alert = True
    col.label(text=problem, icon="ERROR")
    col.label(text="Regenerate rebuilds it from its targets (or its metaballs)")
