"""Snow Brush in blender -b (issue 15): scripted strokes add snow under the brush where the snowfall reaches, erase
it, and are undone byte for byte; the metaballs stay the snow's source of truth."""

import bpy
import numpy as np
import pytest

from firn.common.core import firncore
from scene_helpers import density_at, select_only


@pytest.fixture
def snowy_floor(clean_scene):
    """A 4 m floor under 0.1 m of snow, with a table (1 m square, 0.8 m high) sheltering its middle."""
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    floor = bpy.context.object
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 0.8), scale=(1.0, 1.0, 0.05))
    select_only(floor)
    assert bpy.ops.firn.add_snow_layer(depth=0.1) == {"FINISHED"}
    return bpy.context.object


def stroke(points, **settings):
    """A scripted stroke through `points` (world m, on the floor) with full pressure."""
    elements = [{"name": "", "location": point, "mouse": (0, 0), "mouse_event": (0, 0), "pressure": 1.0,
                 "size": 0, "pen_flip": False, "time": 0.0, "is_start": i == 0, "x_tilt": 0.0, "y_tilt": 0.0}
                for i, point in enumerate(points)]
    return bpy.ops.firn.snow_brush(stroke=elements, **settings)


def grid_file(snow):
    return bpy.path.abspath(snow.data.filepath)


def test_stroke_adds_snow_only_under_the_brush(snowy_floor):
    snow = snowy_floor
    balls = len(snow.firn.metaballs.data.vertices)
    above_old_top = [(1.2, 0.0, 0.14), (1.2, 1.0, 0.14), (-1.2, 0.0, 0.14)]
    assert density_at(snow, *above_old_top).tolist() == [0.0, 0.0, 0.0]
    points = [(1.2, y, 0.1) for y in (-0.1, 0.0, 0.1)]
    assert stroke(points, mode="ADD", radius=0.3, strength=0.05) == {"FINISHED"}
    under, beside, far = density_at(snow, *above_old_top)
    assert under > 50.0 and beside == 0.0 and far == 0.0
    assert len(snow.firn.metaballs.data.vertices) > balls  # the stroke's balls, kept with the snow


def test_no_snow_lands_under_the_table(snowy_floor):
    snow = snowy_floor
    path, balls = grid_file(snow), len(snow.firn.metaballs.data.vertices)
    assert stroke([(0.0, 0.0, 0.0), (0.1, 0.0, 0.0)], mode="ADD", radius=0.2, strength=0.1) == {"FINISHED"}
    assert len(snow.firn.metaballs.data.vertices) == balls
    assert grid_file(snow) == path  # nothing landed: the same file
    assert density_at(snow, (0.0, 0.0, 0.02), (0.1, 0.0, 0.05)).tolist() == [0.0, 0.0]


def test_erase_removes_the_snow_under_the_brush(snowy_floor):
    snow = snowy_floor
    assert density_at(snow, (1.2, 0.0, 0.03))[0] > 100.0
    assert stroke([(1.2, 0.0, 0.1)], mode="ERASE", radius=0.3, strength=0.5) == {"FINISHED"}
    erased, kept = density_at(snow, (1.2, 0.0, 0.03), (-1.2, 0.0, 0.03))
    assert erased == 0.0 and kept > 100.0


def test_undo_gives_back_the_grids_byte_for_byte(snowy_floor):
    name, path = snowy_floor.name, grid_file(snowy_floor)
    before = open(path, "rb").read()
    balls = len(snowy_floor.firn.metaballs.data.vertices)
    bpy.ops.ed.undo_push(message="before the stroke")
    assert stroke([(1.2, 0.0, 0.1), (1.3, 0.0, 0.1)], mode="ADD", radius=0.3, strength=0.05) == {"FINISHED"}
    assert grid_file(bpy.data.objects[name]) != path
    bpy.ops.ed.undo_push(message="Snow Brush")  # what Blender does after an operator run from the UI
    bpy.ops.ed.undo()
    snow = bpy.data.objects[name]
    assert grid_file(snow) == path and open(path, "rb").read() == before
    assert len(snow.firn.metaballs.data.vertices) == balls
    # The brush works on the snow undo gave back (its kept canvas no longer matches the file).
    assert stroke([(-1.2, 0.0, 0.1)], mode="ERASE", radius=0.3, strength=0.5) == {"FINISHED"}
    assert density_at(bpy.data.objects[name], (1.2, 0.0, 0.14), (-1.2, 0.0, 0.03)).tolist() == [0.0, 0.0]


def test_rebuild_from_metaballs_gives_the_painted_snow(snowy_floor):
    snow = snowy_floor
    stroke([(1.0, y, 0.1) for y in np.linspace(-0.5, 0.5, 6)], mode="ADD", radius=0.3, strength=0.05)
    stroke([(1.0, 0.0, 0.15)], mode="SMOOTH", radius=0.4, strength=0.03)
    stroke([(-1.0, 0.5, 0.1)], mode="ERASE", radius=0.3, strength=0.04)
    painted = grid_file(snow)
    xs = np.linspace(-1.8, 1.8, 37)
    points = np.array([(x, y, z) for x in xs for y in xs[::3] for z in np.linspace(0.0, 0.3, 16)], np.float32)
    expected = {grid: firncore.sample_grid(painted, grid, points) for grid in ("density", "surface")}
    voxels = firncore.grid_statistics(painted, "density")["active_voxels"]
    assert bpy.ops.firn.rebuild_from_metaballs() == {"FINISHED"}
    rebuilt = grid_file(snow)
    assert rebuilt != painted
    for grid, values in expected.items():
        np.testing.assert_array_equal(firncore.sample_grid(rebuilt, grid, points), values)
    assert firncore.grid_statistics(rebuilt, "density")["active_voxels"] == voxels


def test_bad_brush_settings_are_reported(snowy_floor):
    with pytest.raises(RuntimeError, match="radius"):
        stroke([(1.2, 0.0, 0.1)], radius=400.0)
    snowy_floor.firn.metaballs = None
    with pytest.raises(RuntimeError, match="poll"):
        stroke([(1.2, 0.0, 0.1)])


def test_a_reopened_blend_has_the_painted_snow(snowy_floor, tmp_path):
    name = snowy_floor.name
    stroke([(1.2, y, 0.1) for y in (-0.1, 0.0, 0.1)], mode="ADD", radius=0.3, strength=0.05)
    painted = density_at(snowy_floor, (1.2, 0.0, 0.14))[0]
    balls = len(snowy_floor.firn.metaballs.data.vertices)
    blend = str(tmp_path / "painted.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)  # the snow's file moves next to the .blend
    bpy.ops.wm.open_mainfile(filepath=blend)
    snow = bpy.data.objects[name]
    assert len(snow.firn.metaballs.data.vertices) == balls
    assert density_at(snow, (1.2, 0.0, 0.14))[0] == painted > 50.0
    # And the brush goes on painting the reopened snow.
    assert stroke([(1.2, 0.0, 0.1)], mode="ERASE", radius=0.3, strength=0.5) == {"FINISHED"}
    assert density_at(bpy.data.objects[name], (1.2, 0.0, 0.03))[0] == 0.0
