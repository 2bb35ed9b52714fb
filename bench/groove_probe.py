"""A V-groove of bumpy_plate's snow under a high sun: the bake against the core's Monte Carlo across the groove, from
its floor's line up one wall (docs/benchmarks.md, plate-near). Light that leaves one wall and enters the other
within a voxel of air is carried in the truth near the floor's line only; far up the wall the groove is a tilted
plane.

The snow lies under z = floor + |x - middle| tan(angle) (two planes, each antialiased along its own normal,
fill 0.5 - distance / h, the larger of the two fills), 48 x 48 x 32 voxels; the sun comes along the groove
(azimuth 90) at --elevation; sky alone with --sky. --plane: the wall rising to +x alone; --along-z: both
antialiased along z alone, as bake_suite.bumpy is (a staircase). Per probe (u voxels from the floor's line across,
up the wall) 4 rays from above along --ray (towards the camera), spread along the groove; channel G, the mean of
the 4. About 25 s at 1024 paths on one core (50 s at the default 2048).

    PYTHONPATH=build/python /usr/bin/python3 bench/groove_probe.py [--angle 45] [--elevation 60] [--sky] [--plane]
        [--along-z] [--samples 2048]
"""
import argparse
import math
import os
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402

SHAPE = (48, 48, 32)  # voxels
FLOOR = 4.0  # voxels: the floor's line above the grid's z = 0
PROBES = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 10.0)  # voxels across from the floor's line


def groove(angle, plane=False, along_z=False):
    """Fill (0-1) of the V-groove (module docstring), or of its wall rising to +x alone (`plane`), and the floor
    line's x (voxels). `along_z`: antialiased along z alone, as bake_suite.bumpy is (a staircase)."""
    X, Y, Z = bake_suite.grid(SHAPE)
    middle = (SHAPE[0] - 1) / 2 + 0.23  # off the grid's nodes
    s, c = math.sin(angle), math.cos(angle)
    left = (Z - FLOOR) * c + (X - middle) * s  # distance (voxels) above the wall that rises towards -x
    right = (Z - FLOOR) * c - (X - middle) * s
    if along_z:
        rise = (X - middle) * math.tan(angle)
        top = FLOOR + (rise if plane else np.abs(rise))
        fill = np.clip(top - Z + 0.5, 0.0, 1.0)
    else:
        fill = np.clip(0.5 - (right if plane else np.minimum(left, right)), 0.0, 1.0)
    fill[:, :, 0] = 0.0
    fill[:2], fill[-2:], fill[:, :2], fill[:, -2:] = 0.0, 0.0, 0.0, 0.0
    return fill, middle


def probe_rays(angle, middle, ray, h):
    """Origins and directions (m) of PROBES' rays: 4 each, from above the grid towards the wall rising to +x."""
    w = ray / np.linalg.norm(ray)
    origins = []
    for u in PROBES:
        for dy in (-1.5, -0.5, 0.5, 1.5):
            surface = np.array([middle + u, SHAPE[1] / 2 + dy, FLOOR + u * math.tan(angle)]) * h
            origins.append(surface + (SHAPE[2] + 1 - surface[2] / h) * h / w[2] * w)
    return np.array(origins), np.tile(-w, (len(origins), 1))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="bumpy_plate", help="the suite case whose optics and voxel the snow takes")
    parser.add_argument("--angle", type=float, default=45.0, help="the walls' slope (deg)")
    parser.add_argument("--elevation", type=float, default=60.0, help="the sun's (deg)")
    parser.add_argument("--sky", action="store_true", help="a uniform sky alone instead of the sun")
    parser.add_argument("--plane", action="store_true", help="the wall rising to +x alone (no groove)")
    parser.add_argument("--along-z", action="store_true", help="antialiased along z alone (bumpy_plate's staircase)")
    parser.add_argument("--ray", default="0,0.35,1", help="towards the camera (grid axes)")
    parser.add_argument("--samples", type=int, default=2048)
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    h = case.voxel
    angle = math.radians(args.angle)
    fill, middle = groove(angle, args.plane, args.along_z)
    origins, directions = probe_rays(angle, middle, np.array([float(x) for x in args.ray.split(",")]), h)
    e = math.radians(args.elevation)
    suns = [] if args.sky else [firncore.SunLight((0.0, math.cos(e), math.sin(e)), (1.0,) * 3, 0.0093)]
    sky = firncore.Sky((1.0,) * 3) if args.sky else None
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "groove.vdb")
        bake_suite.write_density(path, fill * case.density.max(), h)
        truth, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=suns, sky=sky,
                                                     samples=args.samples, seed=11)
        firncore.bake(path, case.optics, suns=suns, sky=sky, quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, origins, directions)
    light = "sky alone" if args.sky else f"sun at {args.elevation:g} deg along the groove"
    shape = ("one wall" if args.plane else "V-groove walls") + (" (filled along z)" if args.along_z else "")
    print(f"{args.case}'s snow, {shape} at {args.angle:g} deg, {light}, {args.samples} paths (channel G)")
    print(f"{'u (voxels)':>10s} {'Monte Carlo':>12s} {'+-':>7s} {'bake':>8s} {'error':>8s}")
    for k, u in enumerate(PROBES):
        rows = slice(4 * k, 4 * k + 4)
        m, b = truth[rows, 1].mean(), baked[rows, 1].mean()
        noise = math.sqrt((error[rows, 1] ** 2).sum()) / 4
        print(f"{u:10.1f} {m:12.4f} {noise:7.4f} {b:8.4f} {100 * (b / m - 1):+7.1f} %")


if __name__ == "__main__":
    main()
