"""The viewport proxy (issue 17) on the car sample's snow: build time, triangles, and what it adds to the .blend.

bench/run.sh bench/proxy_bench.py [-- --runs N]   (blender -b with the add-on from the build tree)
Prints markdown rows. Goal: the proxy built in <= 0.5 s. Timings vary with the machine's load; the fastest of
N runs is reported.
"""

import argparse
import os
import sys
import tempfile

import addon_utils
import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow  # noqa: E402

sys.path.insert(0, HERE)
from timing import fastest  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=3)
    return parser.parse_args(argv)



def blend_size(folder, name):
    path = os.path.join(folder, name)
    bpy.ops.wm.save_as_mainfile(filepath=path, copy=True, compress=False)
    return os.path.getsize(path)


def main():
    args = parse_args()
    addon_utils.enable("firn", default_set=True)
    from firn.snow_layer import proxy

    _scene, targets = car_under_snow.build_scene()
    snow = car_under_snow.add_car_snow(targets)
    path = bpy.path.abspath(snow.data.filepath)
    core_s, arrays = fastest(args.runs, lambda: proxy.mesh_arrays(path, snow.firn.voxel_size))
    store_s, made = fastest(args.runs, lambda: proxy.store_proxy(snow, arrays, 1.0))
    vertices, triangles = arrays
    with tempfile.TemporaryDirectory() as folder:
        with_proxy = blend_size(folder, "with.blend")
        proxy.remove_proxy(snow)
        without = blend_size(folder, "without.blend")
    mesh_bytes = vertices.nbytes + triangles.nbytes  # positions and corner indices: the mesh's own data
    print("| voxel size | proxy triangles | vertices | core: VDB → mesh (s) | Blender mesh + object (s) "
          "| total (s) | .blend growth (MB) | mesh arrays (MB) |")
    print("|---|---|---|---|---|---|---|---|")
    print(f"| {snow.firn.voxel_size * 1000:.0f} mm | {len(triangles):,} | {len(vertices):,} | {core_s:.3f} "
          f"| {store_s:.3f} | {core_s + store_s:.3f} | {(with_proxy - without) / 1e6:.2f} | {mesh_bytes / 1e6:.2f} |")
    assert made is not None


main()
