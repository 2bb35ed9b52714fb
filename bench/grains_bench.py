"""Grain snow (issue 12): Chrisman's accumulation speed, and the albedo of deep piles of ice spheres rendered grain
by grain against Kokhanovsky & Zege (2004).

PYTHONPATH=build/python /usr/bin/python3 bench/grains_bench.py [--scene car.npz] [--grains 1000000] [--paths 40000]
(--scene: triangles written by `bench/run.sh bench/car_triangles.py -- car.npz`; without it a procedural scene of
about the same size is used.) Timings vary with the machine's load; albedos are seeded and repeat exactly.
"""

import argparse
import math
import time

import numpy as np

import firncore

ETA = 1.31
RHO_ICE = 917.0


def procedural_scene(n=72):
    """A 13 m ground with a bumpy 4 m x 2 m 'car' block on it: about 10,000 triangles, like the car sample."""
    xs = np.linspace(-6.5, 6.5, n)
    x, y = np.meshgrid(xs, xs)
    inside = (np.abs(x) < 2.1) & (np.abs(y) < 0.9)
    z = np.where(inside, 1.2 + 0.1 * np.sin(3 * x) * np.cos(3 * y), 0.0)
    vertices = np.stack([x, y, z], -1).reshape(-1, 3).astype(np.float32)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    a = (j * n + i).ravel()
    triangles = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)])
    return vertices, triangles.astype(np.uint32), f"procedural ground + block, {len(triangles)} triangles"


def accumulation(scene, count):
    if scene:
        data = np.load(scene)
        vertices, triangles, name = data["vertices"], data["triangles"], f"car sample, {len(data['triangles'])} triangles"
    else:
        vertices, triangles, name = procedural_scene()
    start = time.perf_counter()
    centres, radii, stats = firncore.accumulate_grains(vertices, triangles, count=count, radius=5e-3,
                                                        radius_variation=0.2, seed=1)
    seconds = time.perf_counter() - start
    print(f"Accumulation on the {name}: {len(radii)} grains of r = 5 mm +- 20 % in {seconds:.1f} s, "
          f"{len(radii) / seconds:,.0f} grains/s")
    print(f"  rays {stats['rays']:,}: missed {stats['missed']:,}, steep {stats['steep']:,}, "
          f"overlapping {stats['overlapping']:,}; highest grain {centres[:, 2].max():.2f} m")


def diffusion_length(radius, gamma, f=0.24):
    """L_d = l_tr / sqrt(3 (1 - omega) / (1 - g)), from the sphere's ray optics (m)."""
    q_abs, g = firncore.grain_sphere_optics(radius, gamma, ETA)
    sigma_t = f * 3 / (4 * radius)
    return 1 / (sigma_t * (1 - g)) / math.sqrt(3 * q_abs / (1 - g))


def kz04_plane(co_albedo, g, mu0=1.0):
    return math.exp(-4 * math.sqrt(co_albedo / (3 * (1 - g))) * 3 / 7 * (1 + 2 * mu0))


def pile(radius, gamma, paths, channel=0, label=None, piles=3):
    """The mean over `piles` piles (each its own seed and paths / piles paths): piles of 10^4-10^5 grains differ
    from one another by ~2 % in albedo, more than the path noise."""
    depth = 6 * diffusion_length(radius, gamma)
    absorption = [0.0, 0.0, 0.0]
    absorption[channel] = gamma
    start = time.perf_counter()
    runs = [firncore.grain_pile_albedo(radius=radius, width=20 * radius, depth=depth, ice_absorption=absorption,
                                       paths=paths // piles, seed=seed) for seed in range(1, piles + 1)]
    white = [firncore.grain_pile_albedo(radius=radius, width=20 * radius, depth=depth, ice_absorption=absorption,
                                        paths=paths // piles // 2, seed=seed, illumination="DIFFUSE")
             for seed in range(1, piles + 1)]
    white_sky = sum(d["albedo"][channel] for d in white) / piles
    white_kz = white[0]["kz04_albedo"][channel]
    seconds = time.perf_counter() - start
    each = [d["albedo"][channel] for d in runs]
    a = sum(each) / piles
    spread = float(np.std(each, ddof=1)) if piles > 1 else 0.0
    se = math.sqrt(sum(d["standard_error"][channel] ** 2 for d in runs)) / piles
    d = runs[0]
    f = sum(r["volume_fraction"] for r in runs) / piles
    kz = d["kz04_albedo"][channel]
    q_abs, g = firncore.grain_sphere_optics(radius, gamma, ETA)
    exact = firncore.slab_monte_carlo(1 - q_abs, g, math.inf, 1.0, 100_000, 1)["reflectance"]
    kz_spheres = kz04_plane(2 / 3 * 1.25 * gamma * radius, 0.89)  # KZ04 with the notes' sphere values B, g
    row = (f"| {label or f'{radius * 1e3:g} mm'} | {gamma * radius:.2e} | {d['top'] * 1e3:.0f} | {d['grains']:,} | "
           f"{f:.3f} | {RHO_ICE * f:.0f} | {a:.4f} +- {se:.4f} (piles {spread:.4f}) | {kz:.4f} | {kz_spheres:.4f} | "
           f"{exact:.4f} | {100 * (a / kz - 1):+.1f} % | {100 * ((1 - a) / (1 - kz) - 1):+.1f} % | "
           f"{white_sky:.4f} | {white_kz:.4f} | {100 * (white_sky / white_kz - 1):+.1f} % | "
           f"{d['mean_events']:.0f} | {seconds:.0f} s |")
    return row, f


def implied_optics(radius, gamma, f):
    q_abs, g = firncore.grain_sphere_optics(radius, gamma, ETA)
    sigma_geo = f * 3 / (4 * radius)
    rho = RHO_ICE * f
    kz_sigma = 3 * rho / (2 * RHO_ICE * radius)  # KZ04, Q_ext = 2
    return (f"| {radius * 1e3:g} mm | {sigma_geo:.0f} | {1 - q_abs:.6f} | {g:.4f} | {2 * sigma_geo:.0f} | "
            f"{1 - q_abs / 2:.6f} | {(1 + g) / 2:.4f} | {kz_sigma:.0f} | {1 - 2 / 3 * 1.6 * gamma * radius:.6f} | 0.845 |")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--scene", help=".npz of vertices and triangles (bench/car_triangles.py)")
    parser.add_argument("--grains", type=int, default=1_000_000)
    parser.add_argument("--paths", type=int, default=40_000)
    args = parser.parse_args()

    accumulation(args.scene, args.grains)
    print()
    gamma = firncore.ice_absorption(800e-9)
    print(f"Plane albedo (collimated, mu0 = 1) of deep piles of ice spheres (eta {ETA}) over a black ground, "
          f"{args.paths:,} paths each. Ice at 800 nm (Warren & Brandt 2008): gamma = {gamma:.3f} 1/m. Piles 6 "
          "diffusion lengths deep, 20 r wide between mirror walls. KZ04 (rays): ART plane albedo from the "
          "spheres' own ray optics (omega, g); KZ04 (B 1.25, g 0.89): the notes' values for spheres; exact RT (HG): "
          "photon Monte Carlo of a half-space with the spheres' omega and g and a Henyey-Greenstein phase function; "
          "white-sky: the same piles under a uniform sky (half the paths) against KZ04's spherical albedo exp(-y).")
    print()
    print("| r | gamma r | depth (mm) | grains | f | rho (kg/m^3) | A grains (3 piles) | A KZ04 (rays) | "
          "A KZ04 (B 1.25, g 0.89) | A exact RT (HG) | A vs KZ04 | 1-A vs KZ04 | white-sky grains | r_s KZ04 | "
          "white-sky vs KZ04 | events/path | time |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    fractions = {}
    for radius in (0.1e-3, 0.5e-3, 2e-3):
        row, fractions[radius] = pile(radius, gamma, args.paths)
        print(row)
    red = firncore.grain_pile_albedo(radius=2e-3, width=20e-3, depth=1e-2, paths=1)["ice_absorption"][0]
    row, _ = pile(2e-3, red, args.paths // 2, label="2 mm, Rec.709 red", piles=2)
    print(row)
    clear = firncore.grain_pile_albedo(radius=1e-3, width=20e-3, depth=60e-3, ice_absorption=(0, 0, 0),
                                       ground_albedo=(1, 1, 1), paths=args.paths // 4, seed=3)
    print(f"\nEnergy: clear ice over a white ground: A = {clear['albedo'][0]:.9f} "
          f"({clear['bailed_out']} paths bailed out, {clear['mean_events']:.0f} events/path)")
    print()
    print("Optics the grains imply at 800 nm (per unit volume of the pile) next to KZ04's defaults for irregular grains:")
    print()
    print("| r | sigma_t rays (1/m) | omega rays | g rays | sigma_t +diffraction | omega +diffr. | g +diffr. | "
          "sigma_t KZ04 | omega KZ04 (B 1.6) | g KZ04 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for radius, f in fractions.items():
        print(implied_optics(radius, gamma, f))


if __name__ == "__main__":
    main()
