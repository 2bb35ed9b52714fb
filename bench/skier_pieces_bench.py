"""What the skier frame's error is made of (docs/benchmarks.md, skier-frame): the frame's lumps (a folder built by
bench/skier_light_bench.py) under its sun alone, no occluders, baked (DRAFT) and rendered from the side as that
bench does, against firncore.monte_carlo_radiance (references kept in the folder):
  1. all the lumps; the view's rays sorted by what each meets first: the sun's optical depth from that point
     through other pieces (0: the piece is lit as if alone), and the ray's optical depth through that piece;
  2. one piece in ten in place, the other nine 3 m below out of view (the voxel count, and so the small-piece
     path of bake.cpp, kept): the pieces alone, against a reference of the kept pieces only.
Pieces: voxels connected through faces, edges or corners, as bake_thin_snow.cpp's pieceAround.

PYTHONPATH=build/python /usr/bin/python3 bench/skier_pieces_bench.py [--folder /tmp/firn_skier_light] [--samples 64]
    [--source-scale N]  (the bake's source grids N density voxels each; 0: as the budget gives, 3-4 here)
"""

import argparse
import json
import os
import sys
import time

import numpy as np
import pyopenvdb

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from block_compare import compare  # noqa: E402
from skier_light_bench import side_view  # noqa: E402

NEIGHBOURS = [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1) if (i, j, k) > (0, 0, 0)]


def read_density(path):
    grid = pyopenvdb.read(path, "density")
    lo, hi = grid.evalActiveVoxelBoundingBox()
    dense = np.zeros([b - a + 1 for a, b in zip(lo, hi)], np.float32)
    grid.copyToArray(dense, ijk=lo)
    return dense, np.array(lo), grid.transform.voxelSize()[0]


def pieces(dense):
    """Active voxels (index, sorted linear index) and each one's piece, by min-label propagation."""
    at = np.argwhere(dense > 0)
    shape = np.array(dense.shape)
    linear = (at[:, 0] * shape[1] + at[:, 1]) * shape[2] + at[:, 2]
    a, b = [], []
    for offset in NEIGHBOURS:
        n = at + offset
        inside = np.all((n >= 0) & (n < shape), 1)
        found = np.minimum(np.searchsorted(linear, (n[:, 0] * shape[1] + n[:, 1]) * shape[2] + n[:, 2]), len(at) - 1)
        hit = inside & (linear[found] == (n[:, 0] * shape[1] + n[:, 1]) * shape[2] + n[:, 2])
        a.append(np.nonzero(hit)[0]), b.append(found[hit])
    a, b = np.concatenate(a), np.concatenate(b)
    label = np.arange(len(at))
    while True:
        least = np.minimum(label[a], label[b])
        new = label.copy()
        np.minimum.at(new, a, least), np.minimum.at(new, b, least)
        new = new[new]
        if np.array_equal(new, label):
            return at, linear, np.unique(label, return_inverse=True)[1]
        label = new


def write(path, parts, voxel):
    grid = pyopenvdb.FloatGrid()
    grid.name = "density"
    grid.transform = pyopenvdb.createLinearTransform(voxelSize=voxel)
    for dense, lo in parts:
        grid.copyFromArray(dense, ijk=tuple(int(v) for v in lo), tolerance=0.0)
    pyopenvdb.write(path, grids=[grid])


def first_met(dense, lo, voxel, linear, label, origins, extinction, sun):
    """Per ray (along +y): the first piece (-1: none), the ray's optical depth through it, the sun's optical depth
    from where the ray reaches optical depth 0.5 through other pieces (nearest voxels, quarter-voxel steps)."""
    shape = np.array(dense.shape)
    out = np.full((len(origins), 3), -1.0)
    steps = np.arange(1, 1200)[:, None] * 0.25 * sun

    def piece_of(points):
        return label[np.searchsorted(linear, (points[:, 0] * shape[1] + points[:, 1]) * shape[2] + points[:, 2])]

    for r, (x, _, z) in enumerate(origins):
        i, k = int(round(x / voxel - lo[0])), int(round(z / voxel - lo[2]))
        if not (0 <= i < shape[0] and 0 <= k < shape[2]):
            continue
        tau = dense[i, :, k] * extinction * voxel
        if tau.sum() < 0.5:
            continue
        j = int(np.searchsorted(np.cumsum(tau), 0.5))
        j = j + int(np.argmax(tau[j:] > 0))
        own = piece_of(np.array([[i, j, k]]))[0]
        column = np.nonzero(tau)[0]
        on_ray = np.stack([np.full(len(column), i), column, np.full(len(column), k)], 1)
        through = tau[column][piece_of(on_ray) == own].sum()
        ray = np.rint(np.array([i, j, k]) + steps).astype(int)
        ray = ray[np.all((ray >= 0) & (ray < shape), 1)]
        rho = dense[ray[:, 0], ray[:, 1], ray[:, 2]]
        snow = rho > 0
        other = piece_of(ray[snow]) != own
        out[r] = own, through, rho[snow][other].sum() * extinction * voxel * 0.25
    return out


def table(title, baked, reference, key, edges):
    print(f"  {title}")
    for a, b in zip(edges[:-1], edges[1:]):
        m = (key >= a) & (key < b)
        if m.any():
            print(f"    {a:6g} .. {b:<6g} {m.sum():4d} rays  reference share {reference[m].sum() / reference.sum():.3f}"
                  f"  baked / reference - 1 {100 * (baked[m].sum() / reference[m].sum() - 1):+6.1f} %")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--folder", default="/tmp/firn_skier_light", help="skier_light_bench.py's folder")
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--pixels", type=int, default=48)
    parser.add_argument("--source-scale", type=int, default=0, help="the bake's source_scale (0: its budget's)")
    args = parser.parse_args()
    import firncore

    meta = json.load(open(os.path.join(args.folder, "inputs.json")))
    spray = meta["paths"][1]
    extinction, albedo, g = meta["optics"]
    optics = firncore.VolumeOptics(extinction, tuple(albedo), g)
    suns = [firncore.SunLight(tuple(d), tuple(i), diameter) for d, i, diameter in meta["suns"]]
    dark = firncore.Sky(radiance=(0.0, 0.0, 0.0))
    positions = np.asarray(firncore.read_spray_state(spray[:-len(".vdb")] + ".state").positions)
    n = args.pixels
    X, origins, directions, _ = side_view(positions, n)

    dense, lo, voxel = read_density(spray)
    at, linear, label = pieces(dense)
    sizes = np.bincount(label)
    print(f"{len(at)} lump voxels in {len(sizes)} pieces (voxels per piece: median {np.median(sizes):.0f}, "
          f"10 % under {np.percentile(sizes, 10):.0f}, 10 % over {np.percentile(sizes, 90):.0f}); sun only, no "
          f"occluders, DRAFT, {n} x {n // 2} pixels, reference {args.samples} paths per pixel; "
          f"load {os.getloadavg()[0]:.1f}")

    kept = label % 10 == 0
    alone = np.zeros_like(dense)
    alone[tuple(at[kept].T)] = dense[tuple(at[kept].T)]
    rest = np.where(alone > 0, 0.0, dense).astype(np.float32)
    files = {"all": os.path.join(args.folder, "pieces_all.vdb"),
             "one in ten": os.path.join(args.folder, "pieces_ten.vdb")}
    write(files["all"], [(dense, lo)], voxel)
    write(files["one in ten"], [(alone, lo), (rest, lo - np.array([0, 0, 300]))], voxel)
    reference_of = {"all": files["all"], "one in ten": os.path.join(args.folder, "pieces_ten_alone.vdb")}
    write(reference_of["one in ten"], [(alone, lo)], voxel)
    del rest

    sun = np.asarray(meta["suns"][0][0], float)
    for (name, path), density in zip(files.items(), (dense, alone)):
        met = first_met(density, lo, voxel, linear, label, origins, extinction, sun / np.linalg.norm(sun))
        baked_path = path[:-4] + f"_baked{args.source_scale or ''}.vdb"
        start = time.process_time()
        stats = firncore.bake(path, optics, suns=suns, sky=dark, quality="DRAFT", seed=0, output_path=baked_path,
                              source_scale=args.source_scale)
        print(f"{name}: bake {time.process_time() - start:.1f} processor s, source scale {stats['source_scale']}",
              flush=True)
        saved = path[:-4] + f"_reference_{n}_{args.samples}.npy"
        if not os.path.exists(saved):
            start = time.time()
            np.save(saved, firncore.monte_carlo_radiance(reference_of[name], optics, origins, directions, suns=suns,
                                                         sky=dark, samples=args.samples, seed=1)[0])
            print(f"  reference: {time.time() - start:.0f} s wall, load {os.getloadavg()[0]:.1f}", flush=True)
        reference = np.load(saved).mean(1)
        baked = firncore.render_baked(baked_path, optics, origins, directions)
        compare(name, baked, reference[:, None], X.shape, width=12)
        hit = met[:, 0] >= 0
        share, seen = reference[hit].sum() / reference.sum(), baked.mean(1)[hit].sum() / reference[hit].sum()
        print(f"  rays meeting a piece: {hit.sum()} of {len(hit)}, {100 * share:.1f} % of the reference's light; "
              f"baked / reference - 1 {100 * (seen - 1):+.1f} %")
        if name == "all":
            table("by the sun's optical depth through other pieces to where the ray meets its piece:",
                  baked.mean(1)[hit], reference[hit], met[hit, 2], [0, 0.01, 1, 5, 20, 100, np.inf])
        table("by the ray's optical depth through its piece:",
              baked.mean(1)[hit], reference[hit], met[hit, 1], [0, 5, 10, 20, 40, np.inf])


if __name__ == "__main__":
    main()
