"""A point or spot lamp's light (or the sun's) along one view's blocks, cell by cell, and per view: the core's Monte
Carlo split into the light's exact single scattering and the rest, against the bake's render; and the exact single
scattering as the bake holds it (docs/benchmarks.md, lamp-dark). bench/snow_block_split.py's cells for
bench/lamp_terminator.py's lights (its cached references; no sky).

The ray is cut where it crosses the voxel cells' faces (bench/ray_depth_split.py's cuts); what a cell [a, b] sends to
the camera is T(a) L(a) - T(b) L(b), L the radiance of a ray started there (the baked render's, the Monte Carlo's).
`once`, the single scattering in a cell, is exact: the trilinear density, midpoint rule on 0.25 mm steps, the light's
irradiance facing it (Lamp.irradiance: its own falloff and cone) times the snow's uncollided transmittance marched
towards the lamp's centre (or the sun) on 0.5 mm steps, Henyey-Greenstein at the angle between the light's travel and
the way to the camera; `rest` is the Monte Carlo's less it (light that entered the snow and came back out). `interp`
is `once` with E T at each point the trilinear interpolation of every voxel's exact density-weighted hat mean of E T
(8^3 points): the form the bake's ramp single scattering takes (beamsInRamp's hatAverage) with its values exact. Per
cell also the voxel's density and mu0 (the ball's outward normal at the voxel to the way to the light). An area lamp's
single scattering is not one way's: not offered.

    PYTHONPATH=build/python python3 bench/lamp_block_split.py [--case ball_grey] [--light point|spot|sun]
        [--view 180,0] [--blocks 57,58,59] [--sums] [--samples 2048]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
import lamp_terminator
from ray_depth_split import cuts

STEP = 0.00025  # m, along the camera ray
LAMP_STEP = 0.0005  # m, towards the light


def light_at(case, light, p):
    """The way (unit) from world point p towards the light, its irradiance there facing it (W/m^2, green; no snow) and
    how far to march towards it (m): a lamp's centre, or the sun (light None: 0.2 m, past the snow)."""
    if light is None:
        return lamp_terminator.TOWARDS, case.sun, 0.2
    way = lamp_terminator.centre_of(case) + lamp_terminator.DISTANCE * lamp_terminator.TOWARDS - p
    distance = np.linalg.norm(way)
    return way / distance, light.irradiance(tuple(p), tuple(way / distance))[1], distance


def single_scattering(case, light, origin, direction, a, b):
    """The light's single scattering sent to the camera from the ray's stretch [a, b] (m from the origin)."""
    k, albedo, g = case.sigma_t / case.rho, case.omega[1], case.g
    s = np.arange(STEP / 2, b, STEP)
    rho = bake_suite.trilinear(case.density, (origin + s[:, None] * direction) / case.voxel)
    camera = np.exp(-k * (np.cumsum(rho) - rho / 2) * STEP)
    inside = (s >= a) & (rho > 0)
    total = 0.0
    for j in np.nonzero(inside)[0]:
        p = origin + s[j] * direction
        towards = light_at(case, light, p)[0]
        mu = float(np.dot(direction, towards))  # the scattering angle's cosine (towards the camera)
        phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
        total += k * rho[j] * albedo * phase * irradiance_through_snow(case, light, p[None])[0] * camera[j]
    return total * STEP


def irradiance_through_snow(case, light, points):
    """The light's irradiance (W/m^2, green, facing it) times the snow's uncollided transmittance towards it (a lamp's
    centre) at world points (N, 3), marched on LAMP_STEP steps."""
    k = case.sigma_t / case.rho
    out = np.zeros(len(points))
    for i, p in enumerate(points):
        towards, E, distance = light_at(case, light, p)
        steps = np.arange(LAMP_STEP / 2, distance, LAMP_STEP)[:, None] * towards
        out[i] = E * math.exp(-k * bake_suite.trilinear(case.density, (p + steps) / case.voxel).sum() * LAMP_STEP)
    return out


class HatAverages:
    """Per voxel, the exact density-weighted mean over its trilinear hat of the light's E T (8^3 points): what the
    bake's ramp single scattering holds per voxel (beamsInRamp's hatAverage on 4^3 points)."""

    def __init__(self, case, light):
        self.case, self.light, self.known = case, light, {}
        q = (np.arange(8) + 0.5) / 8 * 2 - 1
        self.offsets = np.stack(np.meshgrid(q, q, q, indexing="ij"), -1).reshape(-1, 3)
        self.hat = np.prod(1 - np.abs(self.offsets), axis=1)

    def __call__(self, c):
        c = tuple(int(x) for x in c)
        if c not in self.known:
            q = np.array(c) + self.offsets
            w = self.hat * bake_suite.trilinear(self.case.density, q)
            inside = w > 0
            lit = irradiance_through_snow(self.case, self.light, q[inside] * self.case.voxel)
            self.known[c] = (w[inside] * lit).sum() / w[inside].sum() if inside.any() else 0.0
        return self.known[c]


def interpolated_single_scattering(case, light, averages, origin, direction, a, b):
    """single_scattering with E T at each point the trilinear interpolation of the voxels' exact hat averages
    (HatAverages): the bake's form with its per-voxel values exact."""
    k, albedo, g = case.sigma_t / case.rho, case.omega[1], case.g
    s = np.arange(STEP / 2, b, STEP)
    rho = bake_suite.trilinear(case.density, (origin + s[:, None] * direction) / case.voxel)
    camera = np.exp(-k * (np.cumsum(rho) - rho / 2) * STEP)
    total = 0.0
    for j in np.nonzero((s >= a) & (rho > 0))[0]:
        p = origin + s[j] * direction
        q = p / case.voxel
        f = np.floor(q).astype(int)
        t = q - f
        ET = sum(np.prod(np.where(o, t, 1 - t)) * averages(f + o)
                 for o in (np.array([(n >> x) & 1 for x in range(3)]) for n in range(8)))
        mu = float(np.dot(direction, light_at(case, light, p)[0]))
        phase = (1 - g * g) / (4 * math.pi * (1 + g * g - 2 * g * mu) ** 1.5)
        total += k * rho[j] * albedo * phase * ET * camera[j]
    return total * STEP


def bake_render(case, light, path, points, along):
    """The render of the grids baked (FINAL, seed 0) under the light alone."""
    firncore.bake(path, case.optics, suns=case.suns() if light is None else [], lamps=[] if light is None else [light],
                  quality="FINAL", seed=0)
    return firncore.render_baked(path, case.optics, points, along)[:, 1]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--case", default="ball_grey")
    parser.add_argument("--light", default="point", choices=["point", "spot", "sun"])
    parser.add_argument("--view", default="180,0", help="azimuth, elevation (deg)")
    parser.add_argument("--blocks", default="", help="blocks within the view, row-major from the bottom")
    parser.add_argument("--samples", type=int, default=2048, help="Monte Carlo paths per cut")
    parser.add_argument("--sums", action="store_true", help="per view the sums: the exact single scattering's share")
    args = parser.parse_args()
    case = bake_suite.case(args.case)
    case.sky = 0.0
    light = lamp_terminator.lamp(args.light, case)
    origins, directions, tau = bake_suite.views(case)
    per = case.pixels ** 2
    cache = os.path.join(tempfile.gettempdir(), "firn_lamp_terminator")
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, case.name + ".vdb")
        bake_suite.write_density(path, case.density, case.voxel)
        reference, _ = lamp_terminator.reference(case, args.light, path, origins, directions,
                                                 lamp_terminator.SAMPLES.get(case.name, 4096), cache)
        reference = reference[:, 1]
        averages = HatAverages(case, light)
        if args.sums:
            print(f"{case.name} {args.light}: per view, the seen blocks' sums over the reference's: its exact single "
                  f"scattering, its rest, the bake; and the single scattering interpolated over the exact (interp)")
            for v, angles in enumerate(case.views):
                seen = np.arange(v * per, (v + 1) * per)[tau[v * per:(v + 1) * per] >= 1.0]
                ref = reference[seen].sum()
                once = sum(single_scattering(case, light, origins[j], directions[j], 0.0, 2.0) for j in seen)
                interp = sum(interpolated_single_scattering(case, light, averages, origins[j], directions[j], 0.0, 2.0)
                             for j in seen)
                baked = bake_render(case, light, path, origins[seen], directions[seen]).sum()
                print(f"  view {str(angles):<9} reference {ref:.4f}: once {once / ref:.3f}, rest {1 - once / ref:.3f}"
                      f", bake {baked / ref:.3f};  interp / once {interp / once:.2f}")
        view = case.views.index(tuple(int(x) for x in args.view.split(",")))
        centre = lamp_terminator.centre_of(case)
        for block in [int(x) for x in args.blocks.split(",") if x]:
            p = view * per + block
            t, T = cuts(case, origins[p], directions[p])
            points = origins[p] + t[:, None] * directions[p]
            along = np.repeat(directions[p][None], len(t), 0)
            render = bake_render(case, light, path, points, along)
            mc, err = firncore.monte_carlo_radiance(path, case.optics, points, along,
                                                    suns=case.suns() if light is None else [],
                                                    lamps=[] if light is None else [light], samples=args.samples,
                                                    seed=23)
            mc, err = mc[:, 1], err[:, 1]
            print(f"{case.name} {args.light} view {args.view} block {block}: reference {reference[p]:.5f}, Monte Carlo "
                  f"from the first cut {mc[0]:.5f} (+- {err[0]:.5f}), render {render[0]:.5f}")
            print("  cell (voxel)  density  mu0    MC        once      rest      interp    bake")
            total = np.zeros(5)
            for j in range(len(t) - 1):
                def sent(L):  # what the cell [t_j, t_j+1] sends to the camera
                    return T[j] * L[j] - T[j + 1] * L[j + 1]
                if sent(mc) == 0.0 and sent(render) == 0.0:
                    continue  # past the ball
                middle = origins[p] + 0.5 * (t[j] + t[j + 1]) * directions[p]
                c = np.round(middle / case.voxel).astype(int)
                rho = case.density[tuple(c)] if all(0 <= c[a] < case.density.shape[a] for a in range(3)) else 0.0
                normal = (c * case.voxel - centre) / np.linalg.norm(c * case.voxel - centre)
                once = single_scattering(case, light, origins[p], directions[p], t[j], t[j + 1])
                interp = interpolated_single_scattering(case, light, averages, origins[p], directions[p], t[j],
                                                        t[j + 1])
                row = np.array([sent(mc), once, sent(mc) - once, interp, sent(render)])
                total += row
                mu0 = normal @ light_at(case, light, c * case.voxel)[0]
                print(f"  {str(tuple(int(x) for x in c)):<13} {rho:6.1f}  {mu0:+.2f}  " +
                      "  ".join(f"{x:+.5f}" for x in row))
            print("  all cells                   " + "  ".join(f"{x:+.5f}" for x in total))


if __name__ == "__main__":
    main()
