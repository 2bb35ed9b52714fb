"""Which way the cluster's lumps send their light under the sun, baked against the core's Monte Carlo (branch
tail-sparse, docs/benchmarks.md "tail-sparse").

cluster_glow_bench.py's scene (B at the centre of 3 x 3 x 3 lumps over black, the sun off every neighbour's line):
  B alone:  B's disk from 14 directions (views_of), per view, against the cosine between the sun and the view.
  around B: the light the neighbours send B, as the bake's gathering reads it: rays from 2 cm off B's centre (just
            outside its snow) outward, cosine-weighted about the outward direction (their sum stands for the
            irradiance over B's surface), binned by the cosine between the sun and the way back to B (-1: B sees a
            neighbour's side away from the sun, the forward light through it).
Usage:
  PYTHONPATH=build/python /usr/bin/python3 bench/lump_angles_bench.py [--samples 32] [--cache DIR]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
from cluster_glow_bench import SUN_TOWARDS, sun_off_the_neighbours
from lumps_between_bench import H, OPTICS_ARGS, cluster_density, plane, views_of


def rays_around(centre, count, seed=3):
    """Rays from 2 voxels off `centre`, each cosine-weighted about its outward direction."""
    rng = np.random.default_rng(seed)
    n = rng.normal(size=(count, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    t = np.cross(n, np.where(np.abs(n[:, 2:]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]))
    t /= np.linalg.norm(t, axis=1)[:, None]
    b = np.cross(n, t)
    u, phi = rng.random(count), 2.0 * math.pi * rng.random(count)
    r = np.sqrt(u)[:, None]
    d = r * (np.cos(phi)[:, None] * t + np.sin(phi)[:, None] * b) + np.sqrt(1.0 - u)[:, None] * n
    return centre + 2.0 * H * n, d


def baked_and_reference(firncore, path, origins, directions, light, samples, cached):
    """Green radiance per ray, baked and the Monte Carlo's (mean, error); `cached`: an .npz file for the latter."""
    optics = firncore.VolumeOptics(*OPTICS_ARGS)
    occluders = [plane(-0.03, 0.0)]
    firncore.bake(path, optics, occluders=occluders, quality="DRAFT", seed=0, source_scale=1, light_tracing=False,
                  **light)
    baked = firncore.render_baked(path, optics, origins, directions, occluders=occluders)[:, 1]
    if cached and os.path.exists(cached):
        reference = np.load(cached)
        return baked, reference["mean"], reference["error"]
    mean, error = firncore.monte_carlo_radiance(path, optics, origins, directions, occluders=occluders,
                                                samples=samples, seed=1, **light)
    if cached:
        np.savez(cached, mean=mean[:, 1], error=error[:, 1])
    return baked, mean[:, 1], error[:, 1]


def report(label, baked, mean, error):
    return (f"{label}: baked {baked.sum():8.3f}, Monte Carlo {mean.sum():8.3f}, "
            f"{100 * (baked.sum() / mean.sum() - 1):+6.1f} % ({100 * math.sqrt((error ** 2).sum()) / mean.sum():.1f})")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=32, help="Monte Carlo paths per ray")
    parser.add_argument("--cache", default=None, help="keep and reuse the Monte Carlo's radiances in this folder")
    args = parser.parse_args()
    import firncore

    sun, towards = sun_off_the_neighbours(firncore), np.array(SUN_TOWARDS)
    path = os.path.join(tempfile.mkdtemp(), "lumps.vdb")

    def cached(name):
        return os.path.join(args.cache, f"{name}_{args.samples}.npz") if args.cache else None

    density, centre, radius = cluster_density(1, False)
    bake_suite.write_density(path, density, H)
    views = 14
    origins, directions = (np.array(a) for a in views_of(centre, radius, views, 16))
    baked, mean, error = baked_and_reference(firncore, path, origins, directions, sun, args.samples, cached("alone"))
    per = len(baked) // views
    print("B alone, per view (cosine between the sun and the view):")
    for v in sorted(range(views), key=lambda v: directions[v * per] @ towards):
        k = slice(v * per, (v + 1) * per)
        print("  " + report(f"{-(directions[v * per] @ towards):+.2f}", baked[k], mean[k], error[k]))

    density, centre, _ = cluster_density(1, True)
    bake_suite.write_density(path, density, H)
    origins, directions = rays_around(centre, 4000)
    baked, mean, error = baked_and_reference(firncore, path, origins, directions, sun, args.samples, cached("around"))
    back = -(directions @ towards)
    print("Around B among the others (cosine between the sun and the way back to B):")
    print("  " + report("all        ", baked, mean, error))
    for lo, hi in ((-1.0, -0.5), (-0.5, 0.0), (0.0, 0.5), (0.5, 1.0)):
        k = (back >= lo) & (back < hi)
        print("  " + report(f"[{lo:+.1f}, {hi:+.1f})", baked[k], mean[k], error[k]))


if __name__ == "__main__":
    main()
