"""Shared by the snow layer tests: selecting objects and reading the snow's density back."""

import os

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


def saved_elsewhere_during(monkeypatch, operator, blend):
    """The user saves the file as `blend` (Save As) while the job of `operator` (a FirnJobMixin class) runs: in
    blender -b its prepare, compute and apply run in a row on the main thread, so the save comes between the
    computation and the apply."""
    compute = operator.compute

    def compute_then_save(inputs, progress):
        result = compute(inputs, progress)
        os.makedirs(os.path.dirname(blend), exist_ok=True)
        assert bpy.ops.wm.save_as_mainfile(filepath=str(blend)) == {"FINISHED"}
        return result

    monkeypatch.setattr(operator, "compute", staticmethod(compute_then_save))


def save_in(folder):
    """Saves the file as scene.blend in a new `folder`."""
    os.makedirs(folder, exist_ok=True)
    assert bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "scene.blend")) == {"FINISHED"}
