"""Snow material presets and operators: the preset menu, saving and removing presets, optics to Custom.

Presets are Blender Python presets (script.execute_preset). Firn's own live in the add-on
(presets/snow_material/), so a reinstall updates them; the user's own are saved where Blender keeps presets
(<user scripts>/presets/firn/snow_material/), which survives reinstalling the add-on. A user preset with the
name of a Firn preset takes its place in the menu.
"""

import os

import bpy
from bl_operators.presets import AddPresetBase

from ..properties import OPTICS_SETTINGS, active_snow
from . import nodes as materials, optics

PRESET_SUBDIR = os.path.join("firn", "snow_material")
SHIPPED_PRESET_DIR = os.path.join(os.path.dirname(__file__), "presets", "snow_material")
# Firn's presets in menu order, from fresh to old to dirty.
SHIPPED_PRESETS = (
    "Fresh_Powder",
    "Settled_Snow",
    "Wind_Packed",
    "Wet_Snow",
    "Old_Snow_and_Firn",
    "Dirty_Snow",
    "Dusty_Snow",
)


def preset_files():
    """[(display name, path)] of every snow material preset: Firn's in order, then the user's alphabetically."""
    paths = {stem: os.path.join(SHIPPED_PRESET_DIR, stem + ".py") for stem in SHIPPED_PRESETS}
    user = {}
    for directory in bpy.utils.preset_paths(PRESET_SUBDIR):
        for name in os.listdir(directory):
            stem, ext = os.path.splitext(name)
            if ext == ".py" and not name.startswith("."):
                user[stem] = os.path.join(directory, name)
    order = list(SHIPPED_PRESETS) + sorted(set(user) - set(SHIPPED_PRESETS), key=str.lower)
    paths.update(user)
    return [(bpy.path.display_name(stem, title_case=False), paths[stem]) for stem in order]


def is_shipped_preset(display_name):
    return any(bpy.path.display_name(stem, title_case=False) == display_name for stem in SHIPPED_PRESETS)


class FIRN_MT_snow_material_presets(bpy.types.Menu):
    bl_label = "Snow Presets"
    bl_idname = "FIRN_MT_snow_material_presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"

    def draw(self, _context):
        layout = self.layout
        for name, path in preset_files():
            props = layout.operator(self.preset_operator, text=name, translate=False)
            props.filepath = path
            props.menu_idname = self.bl_idname


class FIRN_OT_snow_material_preset_add(AddPresetBase, bpy.types.Operator):
    """Save the snow's optics as a preset, or remove the selected preset"""

    bl_idname = "firn.snow_material_preset_add"
    bl_label = "Add Snow Material Preset"
    preset_menu = FIRN_MT_snow_material_presets.bl_idname
    preset_subdir = PRESET_SUBDIR
    preset_defines = ["firn = bpy.context.object.firn"]
    preset_values = [f"firn.{name}" for name in OPTICS_SETTINGS]

    @classmethod
    def poll(cls, context):
        if active_snow(context) is None:
            cls.poll_message_set("Select a Firn snow object")
            return False
        return True

    def execute(self, context):
        removing = self.remove_active or self.remove_name
        name = FIRN_MT_snow_material_presets.bl_label if self.remove_active else self.name
        if removing and is_shipped_preset(name):
            self.report({"WARNING"}, f"'{name}' comes with Firn and cannot be removed")
            return {"CANCELLED"}
        return super().execute(context)


class FIRN_OT_snow_optics_to_custom(bpy.types.Operator):
    """Copy the optics derived from the physical parameters into the Custom fields and switch to Custom"""

    bl_idname = "firn.snow_optics_to_custom"
    bl_label = "Copy to Custom"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = active_snow(context)
        if obj is None or obj.firn.optics_mode != "PHYSICAL":
            cls.poll_message_set("Select a Firn snow object with physical optics")
            return False
        return True

    def execute(self, context):
        settings = context.object.firn
        try:
            volume = optics.volume_optics(settings)
        except ValueError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        settings.extinction_per_density = volume.extinction_per_density
        settings.albedo = volume.albedo
        settings.optics_mode = "CUSTOM"
        return {"FINISHED"}


class FIRN_OT_snow_material_assign(bpy.types.Operator):
    """Give the snow object Firn's snow material again, made from its optics"""

    bl_idname = "firn.snow_material_assign"
    bl_label = "Use Firn Snow Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = active_snow(context)
        if obj is None or obj.type != "VOLUME":
            cls.poll_message_set("Select a Firn snow (volume) object")
            return False
        return True

    def execute(self, context):
        materials.ensure_snow_material(context.object)
        return {"FINISHED"}


classes = (
    FIRN_MT_snow_material_presets,
    FIRN_OT_snow_material_preset_add,
    FIRN_OT_snow_optics_to_custom,
    FIRN_OT_snow_material_assign,
)
