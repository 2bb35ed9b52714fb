"""How the light leaving a snow wall under the sky alone varies with the view's elevation, baked against the core's
Monte Carlo (docs/benchmarks.md, "sky-aim").

bench/wall_on_ground_bench.py's box (bumpy_plate's snow, tau 15 per 1 cm voxel, omega 0.999, g 0.7) on a ground of
albedo 0 or 0.5; rays onto the middle rows of its wall facing +x (heights 4, 5, 6 voxels, 8 columns) from 75 degrees
above the horizon to 50 below, 3 cm out. Printed per elevation: baked / reference - 1 (green, 24 rays summed) and the
reference's mean (1024 paths per ray, noise about 1 %).

    PYTHONPATH=build/python /usr/bin/python3 bench/wall_exit_lean_bench.py
"""
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

H = 0.01  # m
ELEVATIONS = (75, 55, 30, 10, -10, -30, -50)  # of the view above the horizon, degrees


def main():
    density = bs.slab(12, 6) * 300.0
    optics = firncore.VolumeOptics(5.0, (0.999,) * 3, 0.7)
    light = dict(sky=firncore.Sky((0.05,) * 3), suns=[])
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "box.vdb")
        bs.write_density(path, density, H)
        for albedo in (0.0, 0.5):
            ground = [bs.plate(-1.0, 2.0, -1.0, 2.0, 1.5 * H, (albedo,) * 3)]
            firncore.bake(path, optics, occluders=ground, quality="FINAL", seed=0, **light)
            parts = []
            for el in ELEVATIONS:
                e = math.radians(el)
                down = np.array([-math.cos(e), 0.0, -math.sin(e)])
                wall = np.array([[13.5 * H, (y + 0.5) * H, z * H] for y in range(4, 12) for z in (4.0, 5.0, 6.0)])
                origins, directions = wall - 0.03 * down, np.tile(down, (len(wall), 1))
                ref = firncore.monte_carlo_radiance(path, optics, origins, directions, occluders=ground, samples=1024,
                                                    seed=5, **light)[0]
                baked = firncore.render_baked(path, optics, origins, directions, occluders=ground)
                parts.append(f"{el}: {100 * (baked[:, 1].sum() / ref[:, 1].sum() - 1):+.1f} ({ref[:, 1].mean():.4f})")
            print(f"ground {albedo}: " + "; ".join(parts), flush=True)


if __name__ == "__main__":
    main()
