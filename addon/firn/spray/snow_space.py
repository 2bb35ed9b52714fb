"""The spray's inputs in its snow layer's space (docs/spray.md "In Blender"). The core simulates in the snow's
file, whose grids are in the metres the snow layer was generated in; a snow layer moved or rotated since carries
that move in its transform, and the Snow Spray and Tracks, its children, carry it too. What is read in world
space (the emitters' rectangles, the obstacles, the way gravity pulls) is taken into the snow's space here, so
the tracks lie under the skis and the lumps fly where they are thrown, wherever the snow layer stands.
"""

import numpy as np

from ..bake.inputs import Frame
from ..common import scene_geometry
from ..common.errors import UserError

WORLD_DOWN = (0.0, 0.0, -1.0)  # Blender's gravity


def snow_space(snow, scene):
    """bake.inputs.Frame of the snow layer (world metres → its grids' metres). UserError for a scaled layer: the
    spray's lengths, speeds and gravity are metres, and its grids' metres would be another size."""
    space = Frame(snow, scene_geometry.metres_per_unit(scene))
    scale = space.length(1.0)
    if not np.isclose(scale, 1.0, rtol=1e-5):
        raise UserError(f"'{snow.name}' is scaled ({1.0 / scale:.4g} ×): Snow Spray takes a snow layer moved and "
                        "rotated, not scaled. Set its scale back, or scale its ground and Regenerate it")
    return space


def rectangles_in(space, rectangles):
    """The emitters' (F, 3, 3) rectangles (centre, half side u, half side v; world m) in the snow's space."""
    linear, translation = space.world_to_object[:3, :3], space.world_to_object[:3, 3]
    placed = []
    for path in rectangles:
        moved = path @ linear.T  # the half sides turn; the centres turn and move
        moved[:, 0] += translation
        placed.append(moved)
    return placed


def triangles_in(space, objects):
    """(vertices (N, 3) float32 m, triangles) in the snow's space; None (no obstacles) stays None."""
    if objects is None:
        return None
    vertices, triangles = objects
    return space.points(vertices), triangles


def down_in(space):
    """The way gravity pulls, in the snow's space."""
    return space.direction(WORLD_DOWN)
