"""How much of the uniform sky a ball and a slab of ball_issue's snow send back, baked against the core's Monte Carlo
(docs/benchmarks.md, "ball-sky3").

Under a uniform sky a convex piece's view albedo (its radiance summed over the sky it intercepts, sum(L) /
(L_sky sum(1 - T)), one orthographic view) is what leaves over what enters: exactly 1 where the snow absorbs nothing.
Per ball also its view along +x by ring (r / R across the view). --map: the slab seen from above and from the side, one ray per voxel column through the voxels' centres, by distance
to its convex edges.

    PYTHONPATH=build/python python3 bench/sky_convex_albedo.py [--omega 0.98] [--g 0.85] [--radius 0.05] [--map]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

SKY = 0.05  # W/m^2/sr
VOXEL = 0.01  # m
EXTINCTION_PER_DENSITY = 10.0  # m^2/kg: sigma_t 1000/m at 100 kg/m^3, 10 optical depths per voxel


def radiances(path, optics, origins, directions, samples, seed):
    """Green radiance along the rays: baked, and the core's Monte Carlo (exact L_sky (1 - T) at omega 1)."""
    baked = firncore.render_baked(path, optics, origins, directions)[:, 1]
    traced = firncore.monte_carlo_radiance(path, optics, origins, directions, sky=firncore.Sky((SKY,) * 3),
                                           samples=samples, seed=seed)[0][:, 1]
    return baked, traced


def view_albedo(path, density, optics, along, pixels, samples, radius):
    """The view's albedo per sky intercepted, baked and traced, the camera looking along `along`."""
    n = np.array(density.shape)
    centre, half = (n - 1) / 2 * VOXEL, 0.525 * n.max() * VOXEL
    along = np.asarray(along, float) / np.linalg.norm(along)
    u = np.cross(along, [0.0, 0.0, 1.0] if abs(along[2]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(along, u)
    s = ((np.arange(pixels) + 0.5) / pixels * 2.0 - 1.0) * half
    origins = np.array([centre - 3.0 * half * along + a * u + b * v for b in s for a in s])
    baked, traced = radiances(path, optics, origins, np.tile(along, (len(origins), 1)), samples, 5)
    step = VOXEL / 32
    steps = np.arange(0.0, 6.0 * half, step)
    tau = np.array([EXTINCTION_PER_DENSITY * step * bs.trilinear(density, (o + steps[:, None] * along) / VOXEL).sum()
                    for o in origins])
    intercepted = SKY * (1.0 - np.exp(-tau)).sum()
    return baked.sum() / intercepted, traced.sum() / intercepted, rings(origins - centre, along, radius, baked, traced)


def rings(offsets, along, radius, baked, traced):
    """A ball's view by distance from its centre across the view, r / R: traced (in L_sky) and baked / traced."""
    r = np.linalg.norm(offsets - (offsets @ along)[:, None] * along, axis=1) / radius
    return "  ".join(f"r/R {lo}-{hi} {traced[m].mean() / SKY:.3f}, {baked[m].sum() / traced[m].sum():.3f}"
                     for lo, hi in ((0, 0.5), (0.5, 0.8), (0.8, 0.95), (0.95, 1.05), (1.05, 1.2))
                     if (m := (r >= lo) & (r < hi)).any())


def slab_map(path, density, optics, samples):
    """The slab's top by ring from its edge and its side by row: traced and baked in L_sky."""
    n = np.array(density.shape)
    inside = np.arange(2, n[0] - 2)  # the slab's voxel centres across (pad 2)
    rows = np.arange(2, n[2] - 2)
    top = np.array([[x * VOXEL, y * VOXEL, (n[2] + 2) * VOXEL] for y in inside for x in inside])
    baked, traced = radiances(path, optics, top, np.tile([0.0, 0.0, -1.0], (len(top), 1)), samples, 5)
    edge = np.minimum(inside - inside[0], inside[-1] - inside)
    ring = np.minimum.outer(edge, edge).ravel()
    for k in range(4):
        m = ring == k if k < 3 else ring >= 3
        print(f"  top, {'ring ' + str(k) if k < 3 else 'inside'} from the edge: Monte Carlo "
              f"{traced[m].mean() / SKY:.4f} L_sky, baked {100 * (baked[m].sum() / traced[m].sum() - 1):+.1f} %")
    side = np.array([[-2 * VOXEL, y * VOXEL, z * VOXEL] for z in rows for y in inside])
    baked, traced = radiances(path, optics, side, np.tile([1.0, 0.0, 0.0], (len(side), 1)), samples, 6)
    baked, traced = baked.reshape(len(rows), -1), traced.reshape(len(rows), -1)
    middle = slice(len(inside) // 4, 3 * len(inside) // 4)
    print("  side rows bottom to top, baked against Monte Carlo, the middle half of each row: " + " ".join(
        f"{100 * (b[middle].sum() / t[middle].sum() - 1):+.0f}" for b, t in zip(baked, traced)) + " %")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--omega", type=float, default=0.98)
    parser.add_argument("--g", type=float, default=0.85)
    parser.add_argument("--radius", type=float, default=0.05, help="m")
    parser.add_argument("--samples", type=int, default=128, help="Monte Carlo paths per ray")
    parser.add_argument("--pixels", type=int, default=48, help="per side; 24 on 1 cm voxels reads a 10 cm ball 1.5 points off")
    parser.add_argument("--map", action="store_true", help="the slab's rays by distance to its edges")
    args = parser.parse_args()
    optics = firncore.VolumeOptics(EXTINCTION_PER_DENSITY, (args.omega,) * 3, args.g)
    pieces = (("ball", bs.ball(args.radius, VOXEL) * 100.0), ("slab 24 x 24 x 12", bs.slab(24, 12) * 100.0))
    with tempfile.TemporaryDirectory() as folder:
        for name, density in pieces:
            path = os.path.join(folder, "piece.vdb")
            bs.write_density(path, density, VOXEL)
            firncore.bake(path, optics, sky=firncore.Sky((SKY,) * 3), quality="FINAL", seed=0)
            views = [view_albedo(path, density, optics, along, args.pixels, args.samples, args.radius)
                     for along in ((1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (1.0, 1.0, 1.0))]
            print(f"{name} (omega {args.omega}, g {args.g}): view albedo per sky intercepted, baked / Monte Carlo, "
                  "along +x, -z, (1, 1, 1): " + "  ".join(f"{b:.4f} / {t:.4f} ({100 * (b / t - 1):+.1f} %)"
                                                          for b, t, _ in views), flush=True)
            if name == "ball":
                print("  along +x by ring: " + views[0][2])
            if args.map and name.startswith("slab"):
                slab_map(path, density, optics, args.samples)


if __name__ == "__main__":
    main()
