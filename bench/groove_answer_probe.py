"""A groove's answer to the light that crosses it (docs/benchmarks.md, valley-answer): the sun across groove_probe's
V-groove, from -x below the walls' slope, lights the wall rising to +x alone; the wall rising to -x and the floor
take the lit wall's light across the air. Per probe (u voxels across from the floor's line, negative up the dark
wall), channel G, 4 rays along the groove towards --ray:

- the truth's own light (no flight between two snow collisions crosses more than --air voxels of air), its light
  crossing at most once, and all of it (the core's Monte Carlo, FIRN_CUT_AIR / FIRN_CUT_COUNT);
- the bake's own light (no gather, FIRN_BOUNCES 0), FINAL (one gather) and --gathers;
- the light arriving 1 voxel out along the wall's normal (60 rays over its hemisphere): the truth's own light of
  the surfaces it sees, which one gather should read, against the bake's own render there (what it reads);
- R = (one crossing - own) / E, sr^-1: radiance towards the camera per unit of arriving light, truth and bake.

Needs the temporary hooks of bench/valley_answer_hooks.diff applied to the core (`git apply`; concave_split_probe.py
says what they do).

    PYTHONPATH=build/python /usr/bin/python3 bench/groove_answer_probe.py [--angle 55] [--along-z] [--elevation 50]
        [--samples 1024]
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
import probe_hooks  # noqa: E402
import groove_probe  # noqa: E402
import valley_gather_probe as vg  # noqa: E402

PROBES = (-10.0, -6.0, -4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 10.0)  # voxels across, - up the dark wall
MU, AZIMUTHS = vg.MU, 12  # the hemisphere's bands of the cosine to the normal (width 0.2), azimuths per band


def wall_point(angle, middle, u, dy=0.0):
    """The groove's surface (voxels) u voxels across from the floor's line, and its unit normal."""
    z = groove_probe.FLOOR + abs(u) * math.tan(angle)
    n = np.array([-math.sin(angle) * np.sign(u), 0.0, math.cos(angle) if u != 0 else 1.0])
    return np.array([middle + u, groove_probe.SHAPE[1] / 2 + dy, z]), n / np.linalg.norm(n)


def camera_rays(angle, middle, ray, h):
    w = ray / np.linalg.norm(ray)
    origins = []
    for u in PROBES:
        for dy in (-1.5, -0.5, 0.5, 1.5):
            surface = wall_point(angle, middle, u, dy)[0] * h
            origins.append(surface + (groove_probe.SHAPE[2] + 1 - surface[2] / h) * h / w[2] * w)
    return np.array(origins), np.tile(-w, (len(origins), 1))


def hemisphere_rays(angle, middle, h, out=1.0):
    """From `out` voxels out along each probe's normal, MU bands x AZIMUTHS rays over its hemisphere."""
    origins, directions = [], []
    for u in PROBES:
        p, n = wall_point(angle, middle, u)
        for w in vg.hemisphere(n, AZIMUTHS):
            origins.append((p + out * n) * h), directions.append(w)
    return np.array(origins), np.array(directions)


def irradiance(radiance):
    """W/m^2 per probe from the hemisphere rays' radiance (G)."""
    L = radiance.reshape(len(PROBES), len(MU), AZIMUTHS) * MU[None, :, None]
    return 2 * np.pi * 0.2 / AZIMUTHS * L.sum(axis=(1, 2))


def per_probe(radiance):
    return radiance.reshape(len(PROBES), 4).mean(axis=1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="bumpy_plate")
    parser.add_argument("--angle", type=float, default=55.0, help="the walls' slope (deg)")
    parser.add_argument("--elevation", type=float, default=30.0, help="the sun's (deg), from -x")
    parser.add_argument("--along-z", action="store_true", help="filled along z alone (bumpy_plate's staircase)")
    parser.add_argument("--ray", default="0,0.35,1", help="towards the camera (grid axes)")
    parser.add_argument("--air", type=float, default=1.0, help="the crossing cut's air run (voxels)")
    parser.add_argument("--gathers", type=int, default=4)
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--hemisphere-samples", type=int, default=256)
    args = parser.parse_args()
    probe_hooks.require_hooks("valley_answer_hooks.diff")
    case = bake_suite.case(args.case)
    h = case.voxel
    angle = math.radians(args.angle)
    fill, middle = groove_probe.groove(angle, False, args.along_z)
    origins, directions = camera_rays(angle, middle, np.array([float(x) for x in args.ray.split(",")]), h)
    ho, hd = hemisphere_rays(angle, middle, h)
    e = math.radians(args.elevation)
    suns = [firncore.SunLight((-math.cos(e), 0.0, math.sin(e)), (1.0,) * 3, 0.0093)]

    def truth(path, o, d, count, samples):
        os.environ["FIRN_CUT_AIR"], os.environ["FIRN_CUT_COUNT"] = f"{args.air if count >= 0 else 0.0}", f"{count}"
        return firncore.monte_carlo_radiance(path, case.optics, o, d, suns=suns, samples=samples, seed=11)[0][:, 1]

    def bake(path, gathers):
        os.environ["FIRN_BOUNCES"] = f"{gathers}"
        firncore.bake(path, case.optics, suns=suns, quality="FINAL", seed=0)
        return (per_probe(firncore.render_baked(path, case.optics, origins, directions)[:, 1]),
                irradiance(firncore.render_baked(path, case.optics, ho, hd)[:, 1]))

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "groove.vdb")
        bake_suite.write_density(path, fill * case.density.max(), h)
        t_own, t_one, t_all = (per_probe(truth(path, origins, directions, n, args.samples)) for n in (0, 1, -1))
        e_truth = irradiance(truth(path, ho, hd, 0, args.hemisphere_samples))
        (b_own, e_read), (b_one, _), (b_many, _) = (bake(path, n) for n in (0, 1, args.gathers))
    fill_kind = "filled along z" if args.along_z else "antialiased along the normals"
    print(f"{args.case}'s snow, V-groove at {args.angle:g} deg ({fill_kind}), sun at {args.elevation:g} deg from -x, "
          f"camera towards {args.ray}, air cut {args.air:g} voxel, {args.samples} paths (G)")
    print(f"{'u':>5s} | {'truth own':>9s} {'one':>7s} {'all':>7s} | {'bake own':>8s} {'1 gather':>8s} "
          f"{f'{args.gathers} gath.':>8s} | {'own':>6s} {'1 vs one':>8s} {'many vs all':>11s} | "
          f"{'E truth':>7s} {'E read':>7s} | {'R truth':>7s} {'R bake':>7s}")
    for k, u in enumerate(PROBES):
        r_truth, r_bake = (t_one[k] - t_own[k]) / e_truth[k], (b_one[k] - b_own[k]) / e_read[k]
        print(f"{u:5.0f} | {t_own[k]:9.4f} {t_one[k]:7.4f} {t_all[k]:7.4f} | {b_own[k]:8.4f} {b_one[k]:8.4f} "
              f"{b_many[k]:8.4f} | {100 * (b_own[k] / t_own[k] - 1):+5.0f}% {100 * (b_one[k] / t_one[k] - 1):+7.1f}% "
              f"{100 * (b_many[k] / t_all[k] - 1):+10.1f}% | {e_truth[k]:7.4f} {e_read[k]:7.4f} | "
              f"{r_truth:7.3f} {r_bake:7.3f}")


if __name__ == "__main__":
    main()
