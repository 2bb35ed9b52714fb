"""Registers every class, property, menu entry and handler of the add-on, and removes them all again."""

import bpy

from . import (bake, bake_ui, cache, jobs, preferences, properties, snow_layer, snow_material, snow_material_ui,
               ui)

# In dependency order: property groups before the types that point to them; the sidebar before its sub-panels.
_modules = (preferences, properties, cache, jobs, snow_layer, ui, snow_material, snow_material_ui, bake, bake_ui)


def register():
    for module in _modules:
        for cls in module.classes:
            bpy.utils.register_class(cls)
        if hasattr(module, "register_extras"):
            module.register_extras()


def unregister():
    for module in reversed(_modules):
        if hasattr(module, "unregister_extras"):
            module.unregister_extras()
        for cls in reversed(module.classes):
            bpy.utils.unregister_class(cls)
