"""The Bake panels, in the 3D view's Firn sidebar and in Properties > Object. They only draw."""

import textwrap

from ..common.jobs import running_jobs
from ..common.panels import draw_file_problem, panel_pair
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


def draw_bake(layout, obj):
    """The whole Bake UI for one volume object."""
    settings = obj.firn
    col = layout.column()
    col.row().prop(settings, "bake_quality", expand=True)
    col.prop(settings, "bake_seed")
    col.prop(settings, "scatter_thin")
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
    if settings.is_snow:
        draw_file_problem(col, obj.data)
    if not settings.is_snow:
        col.label(text="Its 'density' grid is read as kg/m³ with Firn's snow optics", icon="INFO")


classes = panel_pair("bake", "Firn Bake", lambda context: _volume(context) is not None, draw_bake)
