"""Shared by the snow layer tests: selecting objects and reading the snow's density back."""

import bpy
import numpy as np

from firn.common.core import firncore


def select_only(*objects):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = objects[0] if objects else None


def density_at(snow, *points):
    """Density (kg/m^3) at points given in metres: the grids' space (vdb-contract.md)."""
    path = bpy.path.abspath(snow.data.filepath)
    return firncore.sample_grid(path, "density", np.array(points, np.float32))
