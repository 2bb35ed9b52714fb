"""Where ball_issue's sky deficit lies: between the surface voxels' lobes and the camera (the density ramp the camera
ray crosses, the trilinear source there), or in the light the lobes hold (docs/benchmarks.md, "ball-sky").

ball_issue's snow (sigma_t 1000/m at 100 kg/m^3, omega 0.98, g 0.85) under a uniform sky alone (0.05 W/m^2/sr), FINAL,
green channel, against the core's Monte Carlo:

1. Camera rays started 0, 0.5, 1, 2, 3 and 5 optical depths into the snow (24 rays along the sphere's normal, or at
   mu 0.5 to it, aimed at points on the sphere; the slab's top alike): the radiance the snow beyond each start sends
   back. Where the loss were in the ramp's first optical depths the ratio would change along the ray.
2. One orthographic view (180, 0) of 32 x 32 pixels, binned by the cosine mu between the ray and the sphere's normal
   where the ray reaches optical depth 1 (rays aimed at voxel centres meet a voxel-sized sphere at steeper mu than
   aimed), and the view's albedo: its radiance summed over the sky it intercepts, sum(L) / (L_sky sum(1 - T)).

    PYTHONPATH=build/python python3 bench/ball_sky_split.py [--voxel 0.005] [--cut 50] [--samples 1024]

--cut D clears the partly filled voxels below density D (the fringe) from the density the bake and the Monte Carlo
both see.
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

SKY = 0.05  # W/m^2/sr
RADIUS = 0.05  # m
EXTINCTION_PER_DENSITY = 1000.0 / 100.0  # m^2/kg: sigma_t 1000/m at 100 kg/m^3
OPTICS = firncore.VolumeOptics(EXTINCTION_PER_DENSITY, (0.98,) * 3, 0.85)
DEPTHS = (0.0, 0.5, 1.0, 2.0, 3.0, 5.0)  # optical depths crossed where the rays of part 1 start


def optical_depths(density, voxel, origin, direction, steps):
    """Optical depth reached at each step (m) along the ray, by the trilinear density."""
    rho = bs.trilinear(density, (origin + steps[:, None] * direction) / voxel)
    return EXTINCTION_PER_DENSITY * np.concatenate([[0.0], np.cumsum(rho[:-1] * np.diff(steps))])


def rays_into(density, voxel, slab, mu, count=24, seed=2):
    """Rays towards the surface at cosine mu to its normal and, per ray, its points at the optical depths DEPTHS."""
    rng = np.random.default_rng(seed)
    n = np.array(density.shape)
    centre = (n - 1) / 2 * voxel
    steps = np.arange(0.0, 8.0 * voxel, voxel / 64)
    origins, directions = [], []
    for _ in range(count):
        if slab:
            normal = np.array([0.0, 0.0, 1.0])
            target = np.array([centre[0] + rng.uniform(-4, 4) * voxel, centre[1] + rng.uniform(-4, 4) * voxel,
                               (n[2] - 1) * voxel])  # over the top's middle, in the air above it
        else:
            v = rng.normal(size=3)
            normal = v / np.linalg.norm(v)
            target = centre + RADIUS * normal
        side = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
        side /= np.linalg.norm(side)
        towards = mu * normal + math.sqrt(1.0 - mu * mu) * side  # to the camera
        start = target + 4.0 * voxel * towards
        tau = optical_depths(density, voxel, start, -towards, steps)
        for depth in DEPTHS:
            origins.append(start - steps[min(np.searchsorted(tau, depth), len(steps) - 1)] * towards)
            directions.append(-towards)
    return np.array(origins), np.array(directions)



def along_rays(path, density, voxel, slab, mu, samples):
    """Per start depth: the Monte Carlo's and the bake's mean radiance (in L_sky) and the bake's relative error."""
    origins, directions = rays_into(density, voxel, slab, mu)
    sky = firncore.Sky((SKY,) * 3)
    baked = firncore.render_baked(path, OPTICS, origins, directions)[:, 1].reshape(-1, len(DEPTHS))
    reference = firncore.monte_carlo_radiance(path, OPTICS, origins, directions, sky=sky, samples=samples,
                                              seed=9)[0][:, 1].reshape(-1, len(DEPTHS))
    return "; ".join(f"{d}: {reference[:, j].mean() / SKY:.3f} / {baked[:, j].mean() / SKY:.3f} "
                     f"({100 * (baked[:, j].sum() / reference[:, j].sum() - 1):+.1f} %)" for j, d in enumerate(DEPTHS))


def view(path, density, voxel, pixels, samples):
    """The view's albedo per sky intercepted, and the bake against the Monte Carlo per mu at optical depth 1."""
    n = np.array(density.shape)
    centre = (n - 1) / 2 * voxel
    half = 1.05 * RADIUS
    s = ((np.arange(pixels) + 0.5) / pixels * 2.0 - 1.0) * half
    along = np.array([1.0, 0.0, 0.0])  # the camera at -x looks along +x: the suite's view (180, 0)
    origins = np.array([centre - 3.0 * half * along + np.array([0.0, u, v]) for v in s for u in s])
    directions = np.tile(along, (len(origins), 1))
    baked = firncore.render_baked(path, OPTICS, origins, directions)[:, 1]
    reference = firncore.monte_carlo_radiance(path, OPTICS, origins, directions, sky=firncore.Sky((SKY,) * 3),
                                              samples=samples, seed=5)[0][:, 1]
    steps = np.arange(0.0, 6.0 * half, voxel / 32)
    mu, total = np.full(len(origins), np.nan), np.zeros(len(origins))
    for r, o in enumerate(origins):
        tau = optical_depths(density, voxel, o, along, steps)
        total[r] = tau[-1]
        if tau[-1] >= 1.0:
            p = o + steps[np.searchsorted(tau, 1.0)] * along
            mu[r] = -np.dot((p - centre) / np.linalg.norm(p - centre), along)
    seen = total >= 1.0
    intercepted = (1.0 - np.exp(-total)).sum()
    lines = [f"  albedo per sky intercepted: Monte Carlo {reference.sum() / SKY / intercepted:.4f}, baked "
             f"{baked.sum() / SKY / intercepted:.4f} ({100 * (baked.sum() / reference.sum() - 1):+.1f} %)"]
    for lo, hi in ((0.9, 1.01), (0.75, 0.9), (0.6, 0.75), (0.45, 0.6), (0.3, 0.45), (0.0, 0.3)):
        m = seen & (mu >= lo) & (mu < hi)
        if m.any():
            ratio = baked[m].sum() / reference[m].sum()
            lines.append(f"  mu at tau 1 {lo:.2f}-{min(hi, 1.0):.2f} ({m.sum():3d} pixels): Monte Carlo "
                         f"{reference[m].mean() / SKY:.3f} L_sky, baked / Monte Carlo {ratio:.3f}")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--voxel", type=float, default=0.01, help="m")
    parser.add_argument("--cut", type=float, default=0.0, help="clear voxels below this density (kg/m^3)")
    parser.add_argument("--samples", type=int, default=1024, help="Monte Carlo paths per pixel (4x along the rays)")
    parser.add_argument("--pixels", type=int, default=32)
    args = parser.parse_args()
    ball = bs.ball(RADIUS, args.voxel) * 100.0
    slab = bs.slab(24, 12) * 100.0
    for density in (ball, slab):
        density[density < args.cut] = 0.0
    with tempfile.TemporaryDirectory() as folder:
        for name, density, voxel in (("ball", ball, args.voxel), ("slab", slab, 0.01)):
            path = os.path.join(folder, name + ".vdb")
            bs.write_density(path, density, voxel)
            firncore.bake(path, OPTICS, sky=firncore.Sky((SKY,) * 3), quality="FINAL", seed=0)
            for mu in (1.0, 0.5):
                print(f"{name} (h {voxel * 100:g} cm), mu {mu}: from optical depth d, Monte Carlo / baked in L_sky: "
                      + along_rays(path, density, voxel, name == "slab", mu, 4 * args.samples), flush=True)
            if name == "ball":
                print(f"ball (h {voxel * 100:g} cm), view (180, 0):\n" + view(path, density, voxel, args.pixels,
                                                                              args.samples), flush=True)


if __name__ == "__main__":
    main()
