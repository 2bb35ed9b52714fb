"""The car sample's bake and render cost: bake time per active voxel (FINAL) and Cycles' peak memory rendering it at
500 × 281 pixels, with the baked grids as fine as the density and 2× coarser (the default). Cycles' peak is the
"Peak" of its status line (its own allocations, the dense volume textures included).

    bench/run.sh bench/car_memory.py

It builds the car scene itself (blend_samples/car_under_snow.py, its snow as the sample's): a build is all it needs.
"""

import os
import sys
import tempfile
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import car_under_snow as car  # noqa: E402
import sample_common as common  # noqa: E402


def cycles_peak_mb(scene, path):
    """Renders one sample at 500 × 281 and returns Cycles' peak memory (MB)."""
    return common.render_peak_mb(scene, path, 500, 1)


def bake_with_source_scale(snow, scale):
    """Bake Scattering (FINAL) with the core's source grids at `scale` density voxels; seconds."""
    from firn.common.core import firncore

    bake = firncore.bake
    firncore.bake = lambda *args, **kwargs: bake(*args, source_scale=scale, **kwargs)
    try:
        started = time.perf_counter()
        common.bake([snow])
        return time.perf_counter() - started
    finally:
        firncore.bake = bake


def main():
    from firn.common.core import firncore

    scene, targets = car.build_scene()
    snow = car.add_car_snow(targets)
    path = bpy.path.abspath(snow.data.filepath)
    voxels = firncore.grid_statistics(path, "density")["active_voxels"]
    folder = tempfile.mkdtemp(prefix="firn_bench_")
    print(f"firncore {firncore.__version__}, car sample, {os.cpu_count()} threads")
    print("source grids   bake s   us/voxel   Cycles peak MB   file MB")
    for scale in (1, 2):
        seconds = bake_with_source_scale(snow, scale)
        peak = cycles_peak_mb(scene, os.path.join(folder, f"car_{scale}.png"))
        label = "as density" if scale == 1 else f"{scale}x coarser"
        print(f"{label:<13} {seconds:7.1f}   {1e6 * seconds / voxels:8.2f}   {peak:14.0f}   {os.path.getsize(path) / 1e6:7.0f}")
    print(f"(density active voxels: {voxels})")


main()
