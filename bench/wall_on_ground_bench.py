"""A snow wall standing on the ground, under the sky alone or the sun and sky, baked against the core's Monte Carlo
by height on the wall (docs/benchmarks.md, "plate-err": bumpy_plate's cut sides).

A box of bumpy_plate's snow (12 x 12 x 6 voxels of 1 cm, tau 15 per voxel, omega 0.999, g 0.7) on a ground of
albedo 0 or 0.5 (the plane between the empty row under the snow and its lowest voxel); rays onto the wall facing +x
(the sun's side, sun 30 degrees high) at heights 2.25 (the lowest voxel) to 7 voxels, seen from --elevation degrees
above the horizon. Printed per height: baked / reference - 1 (green, 8 rays summed) and the reference's mean.

    PYTHONPATH=build/python /usr/bin/python3 bench/wall_on_ground_bench.py [--elevation 55] [--sun] [--samples 512]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

H = 0.01  # m
HEIGHTS = (2.25, 3.0, 4.0, 5.0, 6.0, 7.0)  # voxels; the ground at 1.5, the wall's top at 7.5
OPTICS = dict(extinction=5.0, albedo=(0.999,) * 3, g=0.7)  # m^2/kg: tau 15 per voxel of the 300 kg/m^3 snow


def baked_box(path, albedo, light):
    """The box written to `path` and baked under `light` on a ground of `albedo`: (albedo, path, optics, ground)."""
    bs.write_density(path, bs.slab(12, 6) * 300.0, H)  # snow in voxels 2..13 (x, y) and 2..7 (z)
    optics = firncore.VolumeOptics(OPTICS["extinction"], OPTICS["albedo"], OPTICS["g"])
    ground = [bs.plate(-1.0, 2.0, -1.0, 2.0, 1.5 * H, (albedo,) * 3)]  # between the empty row 1 and the snow
    firncore.bake(path, optics, occluders=ground, quality="FINAL", seed=0, **light)
    return albedo, path, optics, ground


def baked_boxes(folder, light):
    """The box baked under `light` on each ground (albedo 0, then 0.5)."""
    for albedo in (0.0, 0.5):
        yield baked_box(os.path.join(folder, "box.vdb"), albedo, light)


def wall_rays(heights, elevation, distance):
    """Rays onto the wall facing +x at `heights` (voxels), 8 columns each, seen from `elevation` degrees above the
    horizon, starting `distance` m out."""
    e = math.radians(elevation)
    down = np.array([-math.cos(e), 0.0, -math.sin(e)])
    wall = np.array([[13.5 * H, (y + 0.5) * H, z * H] for y in range(4, 12) for z in heights])
    return wall - distance * down, np.tile(down, (len(wall), 1))


def baked_over_reference(box, rays, light, samples):
    """Green baked / reference - 1 (in %) over `rays` (origins, directions) and the reference's mean."""
    albedo, path, optics, ground = box
    origins, directions = rays
    reference = firncore.monte_carlo_radiance(path, optics, origins, directions, occluders=ground, samples=samples,
                                              seed=5, **light)[0]
    baked = firncore.render_baked(path, optics, origins, directions, occluders=ground)
    return 100 * (baked[:, 1].sum() / reference[:, 1].sum() - 1), reference[:, 1].mean()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--elevation", type=float, default=55.0, help="of the view, degrees")
    parser.add_argument("--sun", action="store_true", help="the sun too (30 degrees high, facing the wall)")
    parser.add_argument("--samples", type=int, default=512)
    args = parser.parse_args()
    light = dict(sky=firncore.Sky((0.05,) * 3),
                 suns=[firncore.SunLight((math.cos(math.pi / 6), 0.0, 0.5), (1.0,) * 3, 0.0093)] if args.sun else [])
    with tempfile.TemporaryDirectory() as folder:
        for box in baked_boxes(folder, light):
            parts = []
            for z in HEIGHTS:
                error, mean = baked_over_reference(box, wall_rays((z,), args.elevation, 0.2), light, args.samples)
                parts.append(f"{z}: {error:+.1f} % ({mean:.4f})")
            print(f"ground {box[0]}, view {args.elevation:g} deg: " + "; ".join(parts), flush=True)

if __name__ == "__main__":
    main()
