"""Registers every class, property, menu entry and handler of the add-on, and removes them all again."""

import bpy

from . import properties
from .bake import operators as bake_operators, sequence as bake_sequence, ui as bake_ui
from .common import cache, jobs, preferences
from .grains import operators as grain_operators
from .material import operators as material_operators, ui as material_ui
from .snow_layer import brush as snow_brush, operators as snow_layer_operators, ui as snow_layer_ui
from .spray import operators as spray_operators, ui as spray_ui

# In dependency order: property groups before the types that point to them; the sidebar (snow_layer_ui) before
# the sub-panels of the other features.
_modules = (preferences, properties, cache, jobs, snow_layer_operators, snow_brush, snow_layer_ui, material_operators,
            material_ui, bake_operators, bake_ui, grain_operators, spray_operators, spray_ui, bake_sequence)


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
