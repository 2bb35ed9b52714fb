"""Snow Spray's panel (Properties > Object and the Firn sidebar): on a snow layer, how to add a spray; on a spray,
what it was made from and what can be done with it. Panels only draw."""

from ..common.jobs import running_jobs
from ..common.panels import panel_pair
from ..properties import SPRAY_PROPERTIES, active_snow_layer, is_lit_sequence, is_spray

ADD_LABEL, BAKE_LABEL = "Add Snow Spray", "Bake Sequence"  # the jobs' labels, the panel shows their progress
_HINTS = ("lump_radius", "track_thickness", "compaction_depth", "voxel_size")  # metres, shown in millimetres too


def draw_spray_settings(layout, holder, names):
    """Add Snow Spray's settings `names`, of the operator (redo panel) or kept on a spray object."""
    col = layout.column()
    col.use_property_split = True
    col.use_property_decorate = False
    for name in names:
        if (name == "vertex_group" and holder.emitter != "VERTEX_GROUP") or \
                (name == "face_index" and holder.emitter != "FACE"):
            continue
        col.prop(holder, name)
        if name in _HINTS:
            col.label(text=f"{getattr(holder, name) * 1e3:.1f} mm")


def _draw_jobs(layout):
    """A running spray job's progress, or False."""
    jobs = [job for job in running_jobs() if job.label in (ADD_LABEL, BAKE_LABEL)]
    if not jobs:
        return False
    row = layout.row(align=True)
    row.label(text=jobs[0].status or jobs[0].label, icon="SORTTIME")
    row.operator("firn.cancel_jobs", icon="CANCEL")
    return True


def draw_spray(layout, obj):
    if not is_spray(obj):
        col = layout.column(align=True)
        col.label(text="Select the animated objects that move through")
        col.label(text="this snow, then this snow last (active)")
        if not _draw_jobs(layout):
            layout.operator("firn.add_snow_spray", icon="MOD_PARTICLES")
        return
    record = obj.firn.spray
    emitters = ", ".join(item.object.name for item in record.emitters if item.object) or "none"
    col = layout.column(align=True)
    col.label(text=f"{'Thrown snow' if record.role == 'SPRAY' else 'Snow with tracks'} of "
                   f"{record.source.name if record.source else '(deleted snow)'}", icon="MOD_PARTICLES")
    col.label(text=f"Emitters: {emitters}")
    col.label(text=f"Frames {record.frame_start}-{record.frame_end}")
    if record.summary:
        col.label(text=record.summary)
    draw_spray_settings(layout, record, SPRAY_PROPERTIES)
    if not _draw_jobs(layout):
        row = layout.row(align=True)
        row.operator("firn.bake_sequence", icon="RENDER_ANIMATION")
        row.operator("firn.clear_snow_spray", text="", icon="TRASH")


def _poll(context):
    """A spray or a snow layer; a layer lit frame by frame has the Firn Bake panel's."""
    return (is_spray(context.object) and not is_lit_sequence(context.object)) or active_snow_layer(context) is not None


classes = panel_pair("snow_spray", "Snow Spray", _poll, draw_spray)
