"""Writes the car sample's snow targets (ground, car, trees; evaluated, world space, m) to an .npz for benchmarks
that run outside Blender (bench/grains_bench.py).

bench/run.sh bench/car_triangles.py -- OUTPUT.npz
"""

import os
import sys

import addon_utils
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow  # noqa: E402


def main():
    output = sys.argv[sys.argv.index("--") + 1]
    addon_utils.enable("firn", default_set=True)
    from firn.common.scene_geometry import world_triangles

    _scene, targets = car_under_snow.build_scene()
    vertices, triangles = world_triangles(targets, bpy.context.evaluated_depsgraph_get())
    np.savez(output, vertices=vertices, triangles=triangles)
    print(f"car scene: {len(triangles)} triangles -> {output}")


main()
