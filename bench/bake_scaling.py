"""Bake time against active voxel count (docs/bake.md, Performance).

A bumpy snow layer 20 voxels deep (1 cm voxels, 300 kg/m^3, one-voxel antialiased top, bumps of +-4 cm so
the snow-to-snow gathering passes run) under a sun and a sky, baked at FINAL quality on all the cores
firncore sees, each size in a fresh process (bench/bake_measure.py). Prints each size's wall and processor time
(all threads), its ratio to the smallest size measured in the same run and the bake's peak memory per voxel.

    PYTHONPATH=build/python python3 bench/bake_scaling.py [sizes in thousands of voxels ...]
"""

import math
import os
import sys
import tempfile

import numpy as np
import pyopenvdb

import bake_measure
import firncore

VOXEL = 0.01  # m
DEPTH = 20  # voxels of snow under the mean surface
DENSITY = 300.0  # kg/m^3


def bumpy_layer(path, voxels):
    side = int(round(math.sqrt(voxels / DEPTH)))
    x = (np.arange(side) - side / 2) * VOXEL
    top = DEPTH + 4.0 * np.sin(2 * np.pi * x[:, None] / 0.5) * np.cos(2 * np.pi * x[None, :] / 0.7)  # voxels
    k = np.arange(DEPTH + 6)
    fill = np.clip(top[:, :, None] - k[None, None, :] + 0.5, 0.0, 1.0).astype(np.float32) * DENSITY
    grid = pyopenvdb.FloatGrid()
    grid.name = "density"
    grid.transform = pyopenvdb.createLinearTransform(voxelSize=VOXEL)
    grid.copyFromArray(fill, tolerance=0.0)
    pyopenvdb.write(path, grids=[grid])
    return grid.activeVoxelCount()


def bake_layer(path, progress=None):
    optics = firncore.VolumeOptics(2000.0 / DENSITY, (0.99997, 0.99999, 0.999999), 0.85)
    sun = firncore.SunLight((0.5, 0.3, 0.8), (3.0, 3.0, 3.0), 0.0093)
    sky = firncore.Sky((0.3, 0.35, 0.45))
    return firncore.bake(path, optics, suns=[sun], sky=sky, quality="FINAL", progress=progress)


def main():
    sizes = [int(s) * 1000 for s in sys.argv[1:]] or [125_000, 500_000, 1_000_000, 2_000_000, 4_000_000]
    print(f"firncore {firncore.__version__}, {firncore.hardware_threads()} threads, FINAL quality, "
          f"load average {os.getloadavg()[0]:.1f}")
    print(f"{'voxels':>10} {'unknowns':>10} {'surface':>9} {'time s':>8} {'us/voxel':>9} {'x time':>7} {'x voxels':>9} "
          f"{'cpu s':>7} {'cpu us/voxel':>12} {'B/voxel':>8}")
    base = None
    with tempfile.TemporaryDirectory() as folder:
        for size in sizes:
            path = os.path.join(folder, f"layer_{size}.vdb")
            active = bumpy_layer(path, size)
            stats = bake_measure.measure_fresh(bake_layer, path)
            seconds, cpu = stats["wall_seconds"], stats["cpu_seconds_total"]
            base = base or (seconds, active)
            print(f"{active:>10} {stats['unknowns']:>10} {stats['surface_voxels']:>9} {seconds:>8.2f} "
                  f"{1e6 * seconds / active:>9.2f} {seconds / base[0]:>7.2f} {active / base[1]:>9.2f} "
                  f"{cpu:>7.2f} {1e6 * cpu / active:>12.2f} {stats['peak_bytes'] / active:>8.0f}", flush=True)

if __name__ == "__main__":
    main()
