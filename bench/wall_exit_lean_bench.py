"""How the light leaving a snow wall under the sky alone varies with the view's elevation, baked against the core's
Monte Carlo (docs/benchmarks.md, "sky-aim").

bench/wall_on_ground_bench.py's box (bumpy_plate's snow, tau 15 per 1 cm voxel, omega 0.999, g 0.7) on a ground of
albedo 0 or 0.5; rays onto the middle rows of its wall facing +x (heights 4, 5, 6 voxels, 8 columns) from 75 degrees
above the horizon to 50 below, 3 cm out. Printed per elevation: baked / reference - 1 (green, 24 rays summed) and the
reference's mean (1024 paths per ray, noise about 1 %).

    PYTHONPATH=build/python /usr/bin/python3 bench/wall_exit_lean_bench.py
"""

import tempfile

import firncore
import wall_on_ground_bench

ELEVATIONS = (75, 55, 30, 10, -10, -30, -50)  # of the view above the horizon, degrees


def main():
    light = dict(sky=firncore.Sky((0.05,) * 3), suns=[])
    with tempfile.TemporaryDirectory() as folder:
        for box in wall_on_ground_bench.baked_boxes(folder, light):
            parts = []
            for elevation in ELEVATIONS:
                rays = wall_on_ground_bench.wall_rays((4.0, 5.0, 6.0), elevation, 0.03)
                error, mean = wall_on_ground_bench.baked_over_reference(box, rays, light, 1024)
                parts.append(f"{elevation}: {error:+.1f} ({mean:.4f})")
            print(f"ground {box[0]}: " + "; ".join(parts), flush=True)

if __name__ == "__main__":
    main()
