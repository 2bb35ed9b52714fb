"""The Bake panels, in the 3D view's Firn sidebar and in Properties > Object. They only draw."""

import textwrap

from ..common.jobs import running_jobs
from ..common.panels import draw_file_problem, panel_pair
from ..properties import is_lit_sequence, is_spray
from . import state as bake_state
from .operators import BAKE_LABEL

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


def _draw_buttons(col, obj):
    """Bake Scattering and Clear Bake; Bake Light Sequence (the scene's frames) on a snow layer, and on the Volume
    playing its lit frames (their range) with Clear Light Sequence."""
    settings = obj.firn
    row = col.row(align=True)
    row.scale_y = 1.4
    if is_lit_sequence(obj):
        record = settings.spray
        col.label(text=f"Lit frame by frame: {record.source.name if record.source else '(deleted snow)'}, "
                       f"frames {record.frame_start}-{record.frame_end}", icon="RENDER_ANIMATION")
        bake = row.operator("firn.bake_light_sequence", icon="RENDER_ANIMATION")
        bake.frame_start, bake.frame_end = record.frame_start, record.frame_end
        row.operator("firn.clear_light_sequence", text="", icon="TRASH")
    else:
        bake = row.operator("firn.bake_scattering", icon="RENDER_STILL")
        row.operator("firn.clear_bake", text="", icon="TRASH")
    bake.quality, bake.seed = settings.bake_quality, settings.bake_seed
    if not is_spray(obj) and settings.is_snow:
        frames = col.operator("firn.bake_light_sequence", text="Bake Light Sequence (scene frames)",
                              icon="RENDER_ANIMATION")
        frames.quality, frames.seed = settings.bake_quality, settings.bake_seed


def draw_bake(layout, obj):
    """The whole Bake UI for one volume object."""
    settings = obj.firn
    col = layout.column()
    col.row().prop(settings, "bake_quality", expand=True)
    col.prop(settings, "bake_seed")
    col.prop(settings, "scatter_thin")
    jobs = [job for job in running_jobs() if job.label == BAKE_LABEL]
    if jobs:
        row = col.row(align=True)
        row.label(text=jobs[0].status or "Baking", icon="SORTTIME")
        row.operator("firn.cancel_jobs", icon="CANCEL")
    else:
        _draw_buttons(col, obj)
    _draw_state(col, obj)
    if settings.is_snow:
        draw_file_problem(col, obj.data)
    if not settings.is_snow:
        col.label(text="Its 'density' grid is read as kg/m³ with Firn's snow optics", icon="INFO")


classes = panel_pair("bake", "Firn Bake", lambda context: _volume(context) is not None, draw_bake)
