"""The Bake panels, in the 3D view's Firn sidebar and in Properties > Object. They only draw."""

import textwrap

import bpy

from . import bake_state
from .bake import BAKE_LABEL
from .jobs import running_jobs

_STATE_ICONS = {key: icon for key, _name, _description, icon, _number in bake_state.STATES}


def _volume(context):
    obj = context.object
    return obj if obj is not None and obj.type == "VOLUME" else None


def _draw_state(layout, obj):
    state, changed = bake_state.changes(obj)
    col = layout.column(align=True)
    if state == bake_state.NONE:
        col.label(text="Not baked", icon=_STATE_ICONS[state])
        return
    if state == bake_state.OUTDATED:
        alert = col.column(align=True)
        alert.alert = True
        alert.label(text="Needs re-bake", icon=_STATE_ICONS[state])
        alert.label(text="Changed: " + ", ".join(changed))
    else:
        col.label(text="Baked", icon=_STATE_ICONS[state])
    for line in textwrap.wrap(obj.firn.bake_summary, 38):
        col.label(text=line)


def draw_bake(layout, obj):
    """The whole Bake UI for one volume object."""
    settings = obj.firn
    col = layout.column()
    col.row().prop(settings, "bake_quality", expand=True)
    col.prop(settings, "bake_seed")
    jobs = [job for job in running_jobs() if job.label == BAKE_LABEL]
    row = col.row(align=True)
    if jobs:
        row.label(text=jobs[0].status or "Baking", icon="SORTTIME")
        row.operator("firn.cancel_jobs", icon="CANCEL")
    else:
        row.scale_y = 1.4
        bake = row.operator("firn.bake_scattering", icon="RENDER_STILL")
        bake.quality, bake.seed = settings.bake_quality, settings.bake_seed
        row.operator("firn.clear_bake", text="", icon="TRASH")
    _draw_state(col, obj)
    if not settings.is_snow:
        col.label(text="Its 'density' grid is read as kg/m³ with Firn's snow optics", icon="INFO")


class FIRN_PT_object_bake(bpy.types.Panel):
    bl_label = "Firn Bake"
    bl_idname = "FIRN_PT_object_bake"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return _volume(context) is not None

    def draw(self, context):
        draw_bake(self.layout, context.object)


class FIRN_PT_sidebar_bake(bpy.types.Panel):
    bl_label = "Bake"
    bl_idname = "FIRN_PT_sidebar_bake"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Firn"
    bl_parent_id = "FIRN_PT_sidebar"

    @classmethod
    def poll(cls, context):
        return _volume(context) is not None

    def draw(self, context):
        draw_bake(self.layout, context.object)


classes = (FIRN_PT_object_bake, FIRN_PT_sidebar_bake)
