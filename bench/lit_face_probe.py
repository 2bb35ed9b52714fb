"""One surface point of a flat slab or a ball, the bake against the core's Monte Carlo: is an error curvature or
the flat surface's own (docs/benchmarks.md, ball-snow-lit)?

A bundle of parallel camera rays (n x n over 3 voxels) aimed at one point of the snow's surface: the top's centre
of a wide slab (32 x 32 voxels, 12 deep) or the +x pole of a ball of --radius, both of the optics of a
bench/bake_suite.py case. The sun lies --sun degrees from the point's normal (towards +x on the slab, up on the
ball), the camera --cam "polar:azimuth" degrees about the normal (azimuth 0: the sun's side), so the slab and the
ball see the same local geometry. The core's Monte Carlo (`firncore.monte_carlo_radiance`) against the baked
render (`firncore.render_baked`), channel G, summed over the bundle.

    PYTHONPATH=build/python /usr/bin/python3 bench/lit_face_probe.py --shape slab --sun 30 --cam 0:0 --sky 0
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


def point_frame(shape, case, radius):
    """The snow's density, the surface point, its normal and the tangent the sun leans towards."""
    h, peak = case.voxel, case.density.max()
    if shape == "slab":
        density = bake_suite.slab(32, 12) * peak
        point = bake_suite.slab_top(density, 12, h)
        return density, point, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    density = bake_suite.ball(radius, h) * peak
    centre = (density.shape[0] - 1) / 2 * h
    normal = np.array([1.0, 0.0, 0.0])
    return density, centre + radius * normal, normal, np.array([0.0, 0.0, 1.0])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--shape", default="slab", choices=["slab", "ball"])
    parser.add_argument("--optics", default="ball_snow", help="the bench/bake_suite.py case whose snow to use")
    parser.add_argument("--radius", type=float, default=0.08, help="the ball's radius, m")
    parser.add_argument("--sun", type=float, default=30.0, help="the sun's angle from the normal, degrees")
    parser.add_argument("--cam", default="0:0", help="the camera's polar:azimuth about the normal, degrees")
    parser.add_argument("--sky", type=float, default=0.05, help="uniform sky, W/m^2/sr (0: sun alone)")
    parser.add_argument("--samples", type=int, default=4096, help="Monte Carlo paths per ray")
    parser.add_argument("--n", type=int, default=4,
                        help="rays per side of the bundle (n x n parallel rays over 3 voxels across the point)")
    args = parser.parse_args()
    case = bake_suite.case(args.optics)
    density, point, normal, tangent = point_frame(args.shape, case, args.radius)
    binormal = np.cross(normal, tangent)
    s = math.radians(args.sun)
    sun = math.cos(s) * normal + math.sin(s) * tangent
    polar, azimuth = (math.radians(float(x)) for x in args.cam.split(":"))
    back = math.cos(polar) * normal + math.sin(polar) * (math.cos(azimuth) * tangent + math.sin(azimuth) * binormal)
    u = np.cross(back, [0.3, 0.5, 0.8])
    u /= np.linalg.norm(u)
    v = np.cross(back, u)
    offsets = ((np.arange(args.n) + 0.5) / args.n * 2.0 - 1.0) * 1.5 * case.voxel
    origins = np.array([point + x * u + y * v + 0.5 * back for x in offsets for y in offsets])
    directions = np.tile(-back, (len(origins), 1))
    suns = [firncore.SunLight(tuple(sun), (1.0,) * 3, 0.0093)]
    sky = firncore.Sky((args.sky,) * 3) if args.sky > 0.0 else None
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bake_suite.write_density(path, density, case.voxel)
        mean, error = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=suns, sky=sky,
                                                    samples=args.samples, seed=11)
        firncore.bake(path, case.optics, suns=suns, sky=sky, quality="FINAL", seed=0)
        baked = firncore.render_baked(path, case.optics, origins, directions)
    reference, noise, bake = mean[:, 1].sum(), math.sqrt((error[:, 1] ** 2).sum()), baked[:, 1].sum()
    print(f"{args.shape} of {args.optics}, sun {args.sun:g} deg, camera {args.cam}, sky {args.sky:g}: reference "
          f"{reference / len(origins):.5f} (noise {100 * noise / reference:.1f} %), bake {bake / len(origins):.5f}, "
          f"{100 * (bake / reference - 1.0):+.1f} %")


if __name__ == "__main__":
    main()
