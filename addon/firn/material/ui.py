"""The Snow Material panels, in Properties > Object and in the 3D view's Firn sidebar. They only draw."""

import math
import textwrap

from ..common.panels import panel_pair
from ..properties import active_snow
from . import nodes as materials, optics, structure
from .operators import FIRN_MT_snow_material_presets


def _format(value, fmt):
    return "∞" if math.isinf(value) else fmt.format(value)


def _channel_row(grid, label, values, fmt):
    grid.label(text=label)
    for value in values:
        grid.label(text=_format(value, fmt))


def _draw_presets(layout):
    row = layout.row(align=True)
    row.menu(FIRN_MT_snow_material_presets.bl_idname, text=FIRN_MT_snow_material_presets.bl_label)
    row.operator("firn.snow_material_preset_add", text="", icon="ADD")
    row.operator("firn.snow_material_preset_add", text="", icon="REMOVE").remove_active = True


def _draw_parameters(layout, settings):
    layout.row().prop(settings, "optics_mode", expand=True)
    col = layout.column(align=True)
    if settings.optics_mode == "PHYSICAL":
        col.prop(settings, "grain_radius_um")
        col.prop(settings, "impurity_black_carbon")
        col.prop(settings, "impurity_dust")
        col.prop(settings, "liquid_water")
        col.prop(settings, "absorption_enhancement")
    else:
        col.prop(settings, "extinction_per_density", text="σt/ρ (m²/kg)")
        row = col.row(align=True)
        row.prop(settings, "albedo", text="")
        for index, channel in enumerate("RGB"):
            row.prop(settings, "albedo", index=index, text=channel)
    col.prop(settings, "anisotropy")
    layout.prop(settings, "mean_density")


def _draw_derived(layout, settings):
    box = layout.box()
    box.label(text="At Mean Density")
    derived = optics.derived(settings)
    if derived.error:
        col = box.column(align=True)
        col.alert = True
        for line in textwrap.wrap(derived.error, 38):
            col.label(text=line)
        col.label(text="The material keeps its last valid optics.")
        return
    row = box.row()
    row.label(text=f"σt  {derived.sigma_t:.4g} 1/m")
    row.label(text=f"ℓ*  {derived.transport_mean_free_path * 1000.0:.3g} mm")
    grid = box.grid_flow(row_major=True, columns=4, even_columns=True, align=True)
    for text in ("", "R", "G", "B"):
        grid.label(text=text)
    _channel_row(grid, "Albedo ω", derived.albedo, "{:.5f}")
    _channel_row(grid, "1 − ω", derived.co_albedo, "{:.1e}")
    _channel_row(grid, "White-sky", derived.white_sky_albedo, "{:.3f}")
    _channel_row(grid, "Diffusion cm", [length * 100.0 for length in derived.diffusion_length], "{:.3g}")


def draw_snow_material(layout, obj):
    """The whole Snow Material UI for one snow object."""
    settings = obj.firn
    if obj.type == "VOLUME" and materials.snow_material(obj) is None:
        row = layout.row()
        row.label(text="Not using Firn's snow material", icon="ERROR")
        row.operator("firn.snow_material_assign", text="Use It")
    if materials.is_baked_material(materials.snow_material(obj)):
        layout.label(text="Baked: re-bake to see changes", icon="INFO")
    _draw_presets(layout)
    _draw_parameters(layout, settings)
    _draw_derived(layout, settings)
    if settings.optics_mode == "PHYSICAL":
        layout.operator("firn.snow_optics_to_custom", icon="COPYDOWN")


def _draw_problem(layout, compute):
    """A red line when the structure's settings are out of range (the material keeps its last valid values)."""
    try:
        compute()
    except ValueError as error:
        col = layout.column(align=True)
        col.alert = True
        for line in textwrap.wrap(str(error), 38):
            col.label(text=line)


def draw_snow_structure(layout, obj):
    """Render mode, sub-balls and glints of one snow object."""
    settings = obj.firn
    layout.prop(settings, "render_mode")
    if settings.render_mode == "BAKED" and not materials.shows_bake(obj):
        layout.label(text="Not baked: path tracing the volume (slow)", icon="INFO")
    layout.prop(settings, "sub_balls")
    col = layout.column(align=True)
    col.active = settings.sub_balls and settings.render_mode != "OPAQUE"
    col.prop(settings, "sub_ball_radius")
    col.prop(settings, "sub_ball_variation")
    col.prop(settings, "sub_ball_depth", text="Depth (optical)")
    col.prop(settings, "sub_ball_strength")
    col.prop(settings, "sub_ball_resolve")
    if settings.sub_balls:
        derived = optics.derived(settings)
        if not derived.error:
            _draw_problem(col, lambda: structure.sub_ball_inputs(settings, derived.sigma_t))
    layout.prop(settings, "glints")
    col = layout.column(align=True)
    col.active = settings.glints
    col.prop(settings, "glint_density")
    col.prop(settings, "glint_size")
    col.prop(settings, "glint_roughness")
    if settings.glints:
        _draw_problem(col, lambda: structure.glint_inputs(settings))


classes = (*panel_pair("snow_material", "Snow Material", lambda context: active_snow(context) is not None,
                       draw_snow_material),
           *panel_pair("snow_structure", "Snow Structure", lambda context: active_snow(context) is not None,
                       draw_snow_structure))
