"""A gathered lump's faces: how much each face's own path noise differs, and what paths set per face from it could
buy at the same tracing cost (docs/benchmarks.md, dense-faces).

Reads the DFDUMP lines of a bake with bench/dense_faces_hooks.diff applied and FIRN_DF_DUMP=K (per face open to air
of the gathered traced voxels: voxel, face, lit bit, the bake's own fit along the face's outward normal, then K fits
along it from K independent estimates of the face's own paths each (128 at FINAL on spray_dense), the fit of those K
pooled, and the tracking steps per path). Per group (lit faces, shadowed, all): the spread of one estimate's
relative standard deviation over the faces, the noise bias of one estimate against the pooled one, and the sum of
the faces' variances at the paths they take now against the Neyman allocation at the same tracking steps (N_f
proportional to sqrt(a_f / c_f), which minimises sum a_f / N_f for sum N_f c_f fixed; a_f a face's variance per path,
c_f its steps per path) with the faces' true variances (the K estimates': a bound) and with the variances a bake
could measure from two of them (shrunk halfway to the group's mean).

    FIRN_DF_DUMP=8 PYTHONPATH=build/python python3 bench/bake_suite.py --cases spray_dense 2> dump.txt
    python3 bench/face_variance.py dump.txt
"""

import argparse

import numpy as np

LIT_PATHS, FACE_PATHS = 350, 128  # kLitFacePaths; the faces' own at FINAL on spray_dense


def read(path):
    rows = []
    for line in open(path):
        if not line.startswith("DFDUMP"):
            continue
        t = line.split()
        at = t.index("pooled")
        rows.append((int(t[3]), np.array([float(x) for x in t[5:at]]), float(t[at + 1]), float(t[at + 3])))
    return rows


def allocation(a, c, paths, rng, fits, relative, m):
    """Sum of the faces' variances at `paths` each, Neyman's with the true a, and Neyman's from two estimates."""
    budget = paths * c.sum()
    uniform = (a / paths).sum()
    best = np.sqrt(a / c)
    best *= budget / (best * c).sum()
    measured = []
    for _ in range(50):
        two = np.array([np.var(row[rng.choice(len(row), 2, replace=False)], ddof=1) for row in fits]) * FACE_PATHS
        two /= m ** 2 if relative else m.mean() ** 2
        two = 0.5 * two + 0.5 * two.mean()
        n = np.sqrt(two / c)
        n *= budget / (n * c).sum()
        measured.append((a / n).sum())
    return uniform, (a / best).sum(), float(np.mean(measured)), best


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("dump")
    args = parser.parse_args()
    rows = read(args.dump)
    rng = np.random.default_rng(0)
    print(f"{len(rows)} faces, {sum(r[0] for r in rows)} lit, {len(rows[0][1])} estimates each")
    for name, keep, paths in (("lit", 1, LIT_PATHS), ("shadowed", 0, FACE_PATHS), ("all", None, FACE_PATHS)):
        group = [r for r in rows if keep is None or r[0] == keep]
        fits = np.array([r[1] for r in group])
        pooled = np.array([r[2] for r in group])
        c = np.array([r[3] for r in group])
        m = np.maximum(fits.mean(1), 1e-30)
        rsd = fits.std(1, ddof=1) / m
        q = np.percentile(rsd, [10, 25, 50, 75, 90])
        print(f"{name} ({len(group)}): one estimate's relative sd, 10/25/50/75/90 %: "
              + " ".join(f"{x:.2f}" for x in q) + f"; its mean over the pooled (noise bias) {m.sum() / pooled.sum():.3f}"
              f"; steps per path 25/50/75 %: {np.percentile(c, 25):.0f} {np.median(c):.0f} {np.percentile(c, 75):.0f}")
        for label, relative in (("relative", True), ("absolute", False)):
            a = fits.var(1, ddof=1) * FACE_PATHS / (m ** 2 if relative else m.mean() ** 2)
            uniform, best, measured, n = allocation(a, c, paths, rng, fits, relative, m)
            print(f"  {label} variance summed at {paths} paths each: Neyman {best / uniform:.2f}, from two estimates "
                  f"{measured / uniform:.2f} of it; Neyman's paths {n.min():.0f}..{n.max():.0f} (median "
                  f"{np.median(n):.0f}, {np.mean(n > 2 * paths) * 100:.0f} % over twice, "
                  f"{np.mean(n < paths / 2) * 100:.0f} % under half)")


if __name__ == "__main__":
    main()
