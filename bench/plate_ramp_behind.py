"""How much of bumpy_plate's error lies where cameras see a surface's exit from behind (docs/benchmarks.md,
"plate-ramp").

Each block's camera ray collects the snow's emission with weight sigma_t e^-tau per length; split over the source
grid's voxels by the trilinear hat (the renderer interpolates the grids), the weight on voxels at the surface (snow
voxels with air among their 26 neighbours, and air voxels beside snow: those that carry a surface's exit lobe) whose
outward normal (the density's gradient, smoothed over 3^3) the ray leaves along (n . d > --leaving, d the ray's
travel: the light it sees travels into that surface; -0.2 counts grazing views too) is the block's "behind" share.
Blocks binned by that share: their count, share of the summed |relative error|, mean |error| and bias (baked against
the suite's 4096-path reference, FINAL, seed 0), per view; and the blocks of the outer pixel columns, whose rays run
inside the +-y cut sides' ramps.

    PYTHONPATH=build/python /usr/bin/python3 bench/plate_ramp_behind.py [--leaving 0]
"""

import argparse
import os
import tempfile

import numpy as np

import bake_suite as bs
import firncore

BINS = (0.0, 0.05, 0.2, 0.5, 1.01)


def box_sum(a):
    """Sum over each voxel's 3^3 block (edges wrap: the grid is padded with empty voxels)."""
    out = np.zeros(a.shape)
    for shift in np.ndindex(3, 3, 3):
        out += np.roll(a, np.array(shift) - 1, axis=(0, 1, 2))
    return out


PAD = 3  # empty voxels around the case's density grid


def padded_normals(case):
    """The case's density padded by PAD empty voxels, and its outward unit normals (the gradient over 3^3)."""
    rho = np.pad(case.density, PAD)
    normal = -np.stack(np.gradient(box_sum(rho)), axis=-1)
    return rho, normal / np.maximum(np.linalg.norm(normal, axis=-1, keepdims=True), 1e-12)


def baked_and_reference(case, folder, origins, directions):
    """The case's density file in folder, baked (FINAL, seed 0): its path, the baked render and the suite's cached
    reference."""
    path = os.path.join(folder, case.name + ".vdb")
    bs.write_density(path, case.density, case.voxel)
    reference, _, _ = bs.reference(case, path, origins, directions,
                                   bs.CACHE)
    firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders, quality="FINAL",
                  seed=0)
    return path, firncore.render_baked(path, case.optics, origins, directions, occluders=case.occluders), reference


def behind_share(case, origins, directions, seen, leaving):
    """Per ray: the share of its emission weight on surface voxels seen from behind (the module's docstring)."""
    rho, normal = padded_normals(case)
    snow = rho > 0.0
    near_air = box_sum(~snow) > 0
    near_snow = box_sum(snow) > 0
    at_surface = (snow & near_air) | (~snow & near_snow)
    steps = np.linspace(0.0, 2.0, 8000)
    dl = steps[1] - steps[0]
    share = np.full(len(origins), np.nan)
    for i in np.nonzero(seen)[0]:
        p = (origins[i] + steps[:, None] * directions[i]) / case.voxel + PAD
        sigma = bs.trilinear(rho, p) * case.sigma_t / case.rho
        w = sigma * np.exp(-np.cumsum(sigma) * dl) * dl
        f = np.floor(p).astype(int)
        t = p - f
        behind = np.zeros(len(p))
        for corner in range(8):
            o = np.array([(corner >> a) & 1 for a in range(3)])
            c = np.clip(f + o, 0, np.array(rho.shape) - 1)
            hat = np.prod(np.where(o, t, 1.0 - t), axis=1)
            leaves = normal[c[:, 0], c[:, 1], c[:, 2]] @ directions[i] > leaving
            behind += hat * (at_surface[c[:, 0], c[:, 1], c[:, 2]] & leaves)
        share[i] = (w * behind).sum() / max(w.sum(), 1e-30)
    return share


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--leaving", type=float, default=0.0, help="n . d above which a voxel is seen from behind")
    args = parser.parse_args()
    case = next(c for c in bs.cases() if c.name == "bumpy_plate")
    origins, directions, tau = bs.views(case)
    seen = tau >= 1.0
    share = behind_share(case, origins, directions, seen, args.leaving)
    view = np.repeat(np.arange(len(case.views)), case.pixels ** 2)
    with tempfile.TemporaryDirectory() as folder:
        _, baked, reference = baked_and_reference(case, folder, origins, directions)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(baked / reference - 1.0)
    total = rel[seen].sum()
    print(f"bumpy_plate: mean {100 * rel[seen].mean():.1f} %, bias "
          f"{100 * (baked[seen].sum() / reference[seen].sum() - 1):+.1f} %; blocks by the behind share of their weight")
    print(f"  {'behind share':<13} {'blocks':>6} {'share':>6} {'mean':>6} {'bias':>7}   " +
          "   ".join(f"{str(v):>9} blocks/share/mean/bias" for v in case.views))
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        m = seen & (share >= lo) & (share < hi)
        per_view = []
        for v in range(len(case.views)):
            mv = m & (view == v)
            per_view.append(f"{3 * mv.sum():4d} {100 * rel[mv].sum() / total:5.1f} {100 * rel[mv].mean():5.1f} "
                            f"{100 * (baked[mv].sum() / reference[mv].sum() - 1):+6.1f}" if mv.any() else " " * 23)
        if m.any():
            print(f"  {lo:4.2f}-{min(hi, 1.0):4.2f}     {3 * m.sum():>6} {100 * rel[m].sum() / total:5.1f}% "
                  f"{100 * rel[m].mean():5.1f}% {100 * (baked[m].sum() / reference[m].sum() - 1):+6.1f}%   " +
                  "     ".join(per_view))
    # The suite's pixel grid puts its outer columns at y -0.35 and 29.35 voxels: those rays run along the +-y cut
    # sides inside their ramps, which they see edge-on.
    column = np.tile(np.arange(case.pixels ** 2) % case.pixels, len(case.views))
    edge = (column == 0) | (column == case.pixels - 1)
    for name, m in (("outer columns (along the +-y sides)", seen & edge), ("the other columns", seen & ~edge)):
        print(f"  {name}: {3 * m.sum()} blocks, {100 * rel[m].sum() / total:.1f} % of the summed error, mean "
              f"{100 * rel[m].mean():.1f} %, bias {100 * (baked[m].sum() / reference[m].sum() - 1):+.1f} %; " +
              ", ".join(f"{case.views[v]} {100 * rel[m & (view == v)].mean():.1f} % / "
                        f"{100 * (baked[m & (view == v)].sum() / reference[m & (view == v)].sum() - 1):+.1f} %"
                        for v in range(len(case.views))))
    order = np.argsort(-np.nan_to_num(share, nan=-1.0))[:12]
    print("the blocks of the largest behind share: view, row from the top, column, share, green error")
    for i in order:
        v, p = divmod(int(i), case.pixels ** 2)
        print(f"  {str(case.views[v]):>9} {case.pixels - 1 - p // case.pixels:2d} {p % case.pixels:2d}  "
              f"{share[i]:.2f}  {100 * (baked[i, 1] / reference[i, 1] - 1):+6.1f} %")


if __name__ == "__main__":
    main()
