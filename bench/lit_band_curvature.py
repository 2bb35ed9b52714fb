"""ball_issue's lit band seen from the side against flat snow of the same normal (docs/benchmarks.md, issue-skin): the
sun alone (from +x, 30 deg up), rays along -y at points of the band whose normals are --normals (x, z components),
on balls of ball_issue's snow of radius --radii cm on --voxels, and on flat antialiased half-spaces of those normals
(ramp_skin_profile.plane's: the ball's ramp on 1 cm voxels; four points each): what curvature,
the ramp's thickness in metres and the voxels each add to the band's light, the core's Monte Carlo against the bake.
--exit: the band's point at normal (0.3, 0.1) instead, seen from directions 0-70 deg off its normal towards the sun,
away from it and to the sides (ball_issue itself).

    PYTHONPATH=build/python python3 bench/lit_band_curvature.py [--radii 5,10,20] [--voxels 0.01,0.005]
        [--samples 16384] [--exit]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from ramp_skin_profile import plane

SUN = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])


def unit_normal(nx, nz):
    return np.array([nx, math.sqrt(1.0 - nx * nx - nz * nz), nz])


def against_monte_carlo(case, density, voxel, origins, directions, samples, seed=3):
    """The Monte Carlo's and the bake's radiance (channel G) along the rays."""
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "snow.vdb")
        bake_suite.write_density(path, density, voxel)
        mc, _ = firncore.monte_carlo_radiance(path, case.optics, origins, directions, suns=case.suns(),
                                              samples=samples, seed=seed)
        firncore.bake(path, case.optics, suns=case.suns(), quality="FINAL", seed=0)
        return mc[:, 1], firncore.render_baked(path, case.optics, origins, directions)[:, 1]


def levels(case, args):
    normals = [tuple(float(v) for v in n.split(",")) for n in args.normals.split(";")]
    down = np.repeat(np.array([[0.0, -1.0, 0.0]]), len(normals), 0)
    print(f"the lit band's sun alone seen along -y (x 1000): MC, baked (baked / MC - 1); {args.samples} paths")
    print("snow                 " + "  ".join(f"normal {n} mu0 {unit_normal(*n) @ SUN:.2f}" for n in normals))
    for voxel in (float(v) for v in args.voxels.split(",")):
        for radius in (float(r) / 100.0 for r in args.radii.split(",")):
            density = bake_suite.ball(radius, voxel) * case.density.max()
            centre = (np.array(density.shape) - 1) / 2 * voxel
            origins = np.array([centre + unit_normal(*n) * radius + np.array([0.0, 0.03, 0.0]) for n in normals])
            mc, baked = against_monte_carlo(case, density, voxel, origins, down, args.samples)
            print(f"ball r {100 * radius:g} cm, {100 * voxel:g} cm  " +
                  "  ".join(f"{1000 * m:6.1f} {1000 * b:6.1f} ({100 * (b / m - 1):+4.0f} %)        " for m, b in zip(mc, baked)))
    row = []
    for n in normals:
        fill, middle = plane(unit_normal(*n))
        points = [np.array([dx, 0.0, dz]) for dx, dz in ((0, 0), (0.3, 0.4), (-0.4, 0.2), (0.15, -0.35))]
        origins = np.array([(middle + p) * case.voxel + np.array([0.0, 0.04, 0.0]) for p in points])
        mc, baked = against_monte_carlo(case, fill * case.density.max(), case.voxel, origins, down[:4], args.samples)
        row.append(f"{1000 * mc.mean():6.1f} {1000 * baked.mean():6.1f} ({100 * (baked.sum() / mc.sum() - 1):+4.0f} %)        ")
    print(f"plane, 1 cm           " + "  ".join(row))


def exits(case, args):
    radius = 0.05
    normal = unit_normal(0.3, 0.1)
    tangent = SUN - (SUN @ normal) * normal
    tangent /= np.linalg.norm(tangent)
    side = np.cross(normal, tangent)
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    ways, labels = [], []
    for theta in (0, 30, 50, 70):
        for azimuth, name in ((0, "towards the sun"), (90, "side"), (180, "away"), (270, "other side")):
            if theta == 0 and azimuth:
                continue
            t, a = math.radians(theta), math.radians(azimuth)
            ways.append(math.cos(t) * normal + math.sin(t) * (math.cos(a) * tangent + math.sin(a) * side))
            labels.append(f"{theta:2d} deg {name}")
    ways = np.array(ways)
    mc, baked = against_monte_carlo(case, case.density, case.voxel, centre + normal * radius + 0.03 * ways, -ways,
                                    args.samples, seed=7)
    print(f"ball_issue's band at normal (0.3, 0.1), mu0 {normal @ SUN:.2f}, the sun alone, leaving towards (x 1000):")
    for label, m, b in zip(labels, mc, baked):
        print(f"  {label:22s} MC {1000 * m:6.1f}  baked {1000 * b:6.1f} ({100 * (b / m - 1):+4.0f} %)")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--radii", default="5,10,20", help="cm")
    parser.add_argument("--voxels", default="0.01,0.005", help="m")
    parser.add_argument("--normals", default="0.1,0.1;0.3,0.1;0.3,0.3;0.5,0.1", help="(x, z) components")
    parser.add_argument("--samples", type=int, default=16384)
    parser.add_argument("--exit", action="store_true")
    args = parser.parse_args()
    case = bake_suite.case("ball_issue")
    case.sky = 0.0
    (exits if args.exit else levels)(case, args)


if __name__ == "__main__":
    main()
