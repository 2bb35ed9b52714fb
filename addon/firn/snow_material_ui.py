"""The Snow Material panels, in Properties > Object and in the 3D view's Firn sidebar. They only draw."""

import math
import textwrap

import bpy

from . import materials, optics
from .snow_material import FIRN_MT_snow_material_presets, snow_object


def _triple(values, scale=1.0, fmt="{:.3g}"):
    return "   ".join("∞" if math.isinf(v) else fmt.format(v * scale) for v in values)


def _value_row(layout, label, text):
    split = layout.split(factor=0.45)
    split.label(text=label)
    split.label(text=text)


def _draw_presets(layout):
    row = layout.row(align=True)
    row.menu(FIRN_MT_snow_material_presets.bl_idname, text=FIRN_MT_snow_material_presets.bl_label)
    row.operator("firn.snow_material_preset_add", text="", icon="ADD")
    row.operator("firn.snow_material_preset_add", text="", icon="REMOVE").remove_active = True


def _draw_parameters(layout, settings):
    layout.row().prop(settings, "optics_mode", expand=True)
    col = layout.column()
    col.use_property_split = True
    col.use_property_decorate = False
    if settings.optics_mode == "PHYSICAL":
        col.prop(settings, "grain_radius")
        col.prop(settings, "impurity_black_carbon")
        col.prop(settings, "impurity_dust")
        col.prop(settings, "liquid_water")
        col.prop(settings, "absorption_enhancement")
    else:
        col.prop(settings, "extinction_per_density")
        col.prop(settings, "albedo")
        row = col.row(align=True)
        for index, channel in enumerate("RGB"):
            row.prop(settings, "albedo", index=index, text=channel)
    col.prop(settings, "anisotropy")
    col.prop(settings, "mean_density")


def _draw_derived(layout, settings):
    box = layout.box()
    box.label(text="Derived at Mean Density (R, G, B)")
    derived = optics.derived(settings)
    if derived.error:
        col = box.column(align=True)
        col.alert = True
        for line in textwrap.wrap(derived.error, 48):
            col.label(text=line)
        return
    col = box.column(align=True)
    _value_row(col, "Extinction σt", f"{derived.sigma_t:.4g} 1/m")
    _value_row(col, "Albedo ω", _triple(derived.albedo, fmt="{:.7f}"))
    _value_row(col, "Absorbed 1 − ω", _triple(derived.co_albedo, fmt="{:.2e}"))
    _value_row(col, "Diffusion Length", _triple(derived.diffusion_length, 100.0) + " cm")
    _value_row(col, "Transport Free Path", f"{derived.transport_mean_free_path * 1000.0:.3g} mm")
    split = col.split(factor=0.45)
    split.label(text="White-Sky Albedo")
    row = split.row()
    row.prop(settings, "derived_white_sky_albedo", text="")
    row.label(text=_triple(derived.white_sky_albedo))


def draw_snow_material(layout, obj):
    """The whole Snow Material UI for one snow object."""
    settings = obj.firn
    if obj.type == "VOLUME" and materials.snow_material(obj) is None:
        row = layout.row()
        row.label(text="Not using Firn's snow material", icon="ERROR")
        row.operator("firn.snow_material_assign", text="Use It")
    _draw_presets(layout)
    _draw_parameters(layout, settings)
    _draw_derived(layout, settings)
    if settings.optics_mode == "PHYSICAL":
        layout.operator("firn.snow_optics_to_custom", icon="COPYDOWN")


class FIRN_PT_snow_material(bpy.types.Panel):
    bl_label = "Snow Material"
    bl_idname = "FIRN_PT_snow_material"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return snow_object(context) is not None

    def draw(self, context):
        draw_snow_material(self.layout, context.object)


class FIRN_PT_sidebar_snow_material(bpy.types.Panel):
    bl_label = "Snow Material"
    bl_idname = "FIRN_PT_sidebar_snow_material"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Firn"
    bl_parent_id = "FIRN_PT_sidebar"

    @classmethod
    def poll(cls, context):
        return snow_object(context) is not None

    def draw(self, context):
        draw_snow_material(self.layout, context.object)


classes = (FIRN_PT_snow_material, FIRN_PT_sidebar_snow_material)
