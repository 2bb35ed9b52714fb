"""Firn's data on Blender objects: obj.firn."""

import bpy


class FIRN_ObjectSettings(bpy.types.PropertyGroup):
    is_snow: bpy.props.BoolProperty(
        name="Is Snow",
        description="This volume object holds Firn snow",
        default=False,
    )


classes = (FIRN_ObjectSettings,)


def register_extras():
    bpy.types.Object.firn = bpy.props.PointerProperty(type=FIRN_ObjectSettings)


def unregister_extras():
    del bpy.types.Object.firn
