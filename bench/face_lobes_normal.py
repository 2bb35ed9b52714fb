"""spray_dense's lit lump faces: the faces' lobe pair (tracedSourceByMoments on the face's whole estimate) towards
the face's normal against the face's own Monte Carlo there and against an independent truth (docs/benchmarks.md,
face-lobes). Needs a bake of spray_dense by the core built with bench/face_lobes_hooks.diff (spray-cores' switches
and one SCDUMP line per lump face: lit bit, face, hat share s, the whole estimate's moments, the face's own source
(1 - s) carried + s shown and its carried part in the 39 source directions, the directions), its stderr kept:

    FIRN_SC_FIT=1 [FIRN_SC_PATHS=2048] (bake spray_dense FINAL seed 0 into BAKED.vdb) 2> faces.txt
    PYTHONPATH=build/python:bench python3 bench/face_lobes_normal.py faces.txt BAKED.vdb

The fit is tracedSourceByMoments and source_lobe's render rewritten in numpy (the dump's values reproduce the core's
printed fit, SCFACE, to its digits). The truth as spray_cores_faces.py's: per lit face 8 camera rays along its
inward normal from the air voxel's centre, within a fifth of a voxel of the face's centre, 512 paths each. Then the
pair matched to the face's own source along the normal per face, by three families of feasible pairs keeping a0 and
the first moment along the beams' axis m (a2 kept, the peak's k chosen; the peak's k kept, its weight chosen; the
broad node kept, the peak's k chosen), and by two that give up the broad lobe's first moment across m or its length
(the broad lobe turned towards the normal; its k scaled); each also matched halfway (lambda 0.5).
"""

import sys

import numpy as np

import bake_suite
import firncore
from lobe_noise_fits import prony  # lobePair's nodes

G = 0.85  # spray_dense's g
MAX_K = 0.95  # kMaxLobeAnisotropy
K = 39  # kSourceDirections


def parse(text):
    """The lit faces' SCDUMP lines as dicts."""
    out = []
    for line in open(text):
        if not line.startswith("SCDUMP "):
            continue
        t = line.split()[1:]
        x = np.array(t[2:], float)
        parts, at = {}, 0
        for name, size in [("s", 1), ("l0", 3), ("l1", 9), ("bl0", 3), ("bl1", 9), ("second", 9), ("third", 27),
                           ("own", K), ("carried", K), ("dirs", 3 * K)]:
            parts[name], at = x[at:at + size], at + size
        if not int(t[0]):
            continue
        face = int(t[1])
        n = np.zeros(3)
        n[face // 2] = 1.0 if face % 2 else -1.0
        out.append(dict(face=face, s=parts["s"][0], l0=parts["l0"], l1=parts["l1"].reshape(3, 3),
                        bl0=parts["bl0"], bl1=parts["bl1"].reshape(3, 3), second=parts["second"].reshape(3, 3).T,
                        third=parts["third"].reshape(3, 3, 3).transpose(0, 2, 1), own=parts["own"],
                        carried=parts["carried"], dirs=parts["dirs"].reshape(K, 3), n=n))
    return out


def lobe(l0, l1, w):
    """lobeRadiance: l0 4 pi HG(k, cos), k = min(|l1| / 3 l0, kMaxLobeAnisotropy)."""
    if l0 <= 0.0:
        return 0.0
    length = np.linalg.norm(l1)
    k = min(length / (3.0 * l0), MAX_K)
    mu = l1 @ w / length if length > 0.0 else 0.0
    return l0 * (1.0 - k * k) / (1.0 + k * k - 2.0 * k * mu) ** 1.5


def grey(source, w):
    """The channels' mean of the broad lobe and the peaked lobe towards w (greyRadiance)."""
    l0, l1, p0, p1 = source
    pm = p0.mean()
    return sum(lobe(l0[c], l1[c], w) + (p0[c] / pm * lobe(pm, p1, w) if pm > 0.0 else 0.0) for c in range(3)) / 3.0


def cap(l0, l1):
    for c in range(3):
        length, most = np.linalg.norm(l1[c]), max(l0[c], 0.0)
        if length > most:
            l1[c] *= most / length


def moments(S):
    """a0..a3 along the beams' axis m, and m (tracedSourceByMoments)."""
    a0, first, beam = S["l0"].mean(), S["l1"].sum(0) / 9.0, S["bl1"].sum(0)
    m = beam / np.linalg.norm(beam)
    a1 = first @ m
    t2 = m @ S["second"] @ m
    t3 = sum(m[i] * (m @ S["third"][i] @ m) for i in range(3))
    return a0, a1, G * G * 0.5 * (3.0 * t2 - a0), G ** 3 * 0.5 * (5.0 * t3 - 3.0 * a1 / G), m


def pair(S, m, k_peak, k_broad):
    """The lobes with nodes k_peak > k_broad, per channel l0 and the first moment along m kept."""
    kp = min(k_peak, MAX_K)
    peak = np.array([np.clip((S["l1"][c] @ m / 3.0 - k_broad * S["l0"][c]) / (k_peak - k_broad), 0.0,
                             max(S["l0"][c], 0.0)) for c in range(3)])
    l0, l1 = S["l0"] - peak, np.array([S["l1"][c] - 3.0 * kp * peak[c] * m for c in range(3)])
    cap(l0, l1)
    return l0, l1, peak, kp * peak.sum() * m


def fitted(S):
    a0, a1, a2, a3, m = moments(S)
    nodes = prony(a0, a1, a2, a3) if a1 > 0.0 else None
    if nodes is None:  # the beams' fallback
        l0, l1, peak = S["l0"] - S["bl0"], S["l1"] - S["bl1"], S["bl0"].copy()
        cap(l0, l1)
        k = np.linalg.norm(S["bl1"].sum(0)) / (9.0 * G * peak.mean()) * min(G, MAX_K)
        return (l0, l1, peak, k * peak.sum() * m), m, None
    return pair(S, m, *nodes), m, (a0, a1, a2, a3, nodes)


def root(f, lo, hi, near, n=160):
    """The root of f on [lo, hi] nearest `near` (a grid, then bisection); None without a change of sign."""
    xs = np.linspace(lo, hi, n)
    ys = np.array([f(x) for x in xs])
    best = None
    for i in range(n - 1):
        if np.isfinite(ys[i]) and np.isfinite(ys[i + 1]) and np.sign(ys[i]) != np.sign(ys[i + 1]):
            a, b = xs[i], xs[i + 1]
            for _ in range(40):
                c = 0.5 * (a + b)
                a, b = (c, b) if np.sign(f(c)) == np.sign(f(a)) else (a, c)
            if best is None or abs(0.5 * (a + b) - near) < abs(best - near):
                best = 0.5 * (a + b)
    return best


def families(S, base, m, fit):
    """Per family: (the pair for a parameter, its range, the main fit's value of it)."""
    out = {}
    if fit is not None:
        a0, a1, a2, a3, (kp, kb) = fit

        def keep_a2(k):
            broad = (k * a1 - a2) / (k * a0 - a1)
            ok = broad < k and broad >= -MAX_K and 0.0 <= (a1 - broad * a0) / (k - broad) <= a0
            return pair(S, m, k, broad) if ok else None
        out["a0 a1 a2 kept, the peak's k"] = (keep_a2, a1 / a0 + 1e-4, 1.0, kp)
        out["a0 a1 kept, the peak's weight"] = (lambda b: pair(S, m, kp, b), -MAX_K, min(kp, a1 / a0) - 1e-4, kb)
        out["a0 a1 kept, the peak's k alone"] = (lambda k: pair(S, m, k, kb), max(kb, a1 / a0) + 1e-4, 1.0, kp)
    u = S["n"] - (S["n"] @ m) * m
    u /= np.linalg.norm(u)

    def turned(t):
        l0, l1, p0, p1 = base
        l0, l1 = l0.copy(), l1 + t * l0[:, None] * u[None, :]
        cap(l0, l1)
        return l0, l1, p0, p1

    def scaled(t):
        l0, l1, p0, p1 = base
        l0, l1 = l0.copy(), l1 * t
        cap(l0, l1)
        return l0, l1, p0, p1
    out["broad lobe turned to the normal"] = (turned, -3.0, 3.0, 0.0)
    out["broad lobe's k scaled"] = (scaled, 0.0, 8.0, 1.0)
    return out


def truth_straight_on(case, rows, vdb):
    """Per lit face the baked render and the truth along its inward normal (8 rays, 512 paths each)."""
    h, rng = case.voxel, np.random.default_rng(2)
    O, D, F = [], [], []
    for i, S in enumerate(rows):
        ax = S["face"] // 2
        for _ in range(8):
            q = S["centre"].copy()
            q[ax] += 0.5 * h * S["n"][ax]
            for a in range(3):
                if a != ax:
                    q[a] += (rng.random() - 0.5) * 0.2 * h
            O.append(q + S["n"] * 0.5 * h), D.append(-S["n"]), F.append(i)
    O, D, F = np.array(O), np.array(D), np.array(F)
    baked = firncore.render_baked(vdb, case.optics, O, D).mean(1)
    truth, _ = firncore.monte_carlo_radiance(vdb, case.optics, O, D, suns=case.suns(), sky=case.skies(), samples=512,
                                             seed=3)
    return np.bincount(F, baked) / 8, np.bincount(F, truth.mean(1)) / 8


def main():
    case = bake_suite.case("spray_dense")
    rows = parse(sys.argv[1])
    # The voxel of each face from its SCFACE line (threads interleave the lines: matched by the hat share and the
    # carried source along the normal, which SCFACE prints to 4 and 6 digits).
    where = {}
    for line in open(sys.argv[1]):
        t = line.split()
        if t[0] == "SCFACE" and t[1] == "1":
            where[(t[6], t[7])] = np.array(list(map(int, t[2:5])), float) * case.voxel
    for S in rows:
        S["centre"] = where[(f"{S['s']:.4f}", f"{S['carried'][int(np.argmax(S['dirs'] @ S['n']))]:.6g}")]
    baked, truth = truth_straight_on(case, rows, sys.argv[2])
    normal = [int(np.argmax(S["dirs"] @ S["n"])) for S in rows]
    own = np.array([S["own"][k] for S, k in zip(rows, normal)])
    fits = [fitted(S) for S in rows]
    fit = np.array([grey(f[0], S["dirs"][k]) for f, S, k in zip(fits, rows, normal)])
    L = np.log
    print(f"{len(rows)} lit faces, towards the normal (sum / sum; the median of the per-face ratio):")
    print(f"  fit / own    {fit.sum() / own.sum():.3f}  median {np.median(fit / own):.3f}")
    order = np.argsort(own / fit)
    print(f"  the same without the 5 largest own / fit: {fit[order[:-5]].sum() / own[order[:-5]].sum():.3f}")
    print(f"  own / truth  {own.sum() / truth.sum():.3f}  median {np.median(own / truth):.3f}")
    print(f"  fit / truth  {fit.sum() / truth.sum():.3f}  median {np.median(fit / truth):.3f}")
    print(f"  baked render / truth {baked.sum() / truth.sum():.3f}  median {np.median(baked / truth):.3f}")
    draws = np.random.default_rng(5).integers(0, len(rows), (2000, len(rows)))  # the faces resampled

    def interval(a, b):
        return "[" + " ".join(f"{x:.3f}" for x in np.percentile(a[draws].sum(1) / b[draws].sum(1), [5, 95])) + "]"
    print(f"  90 % intervals over the faces resampled: fit / own {interval(fit, own)}, own / truth "
          f"{interval(own, truth)}, fit / truth {interval(fit, truth)}")
    print(f"  sd of log: truth {L(truth).std():.2f} fit {L(fit).std():.2f} own {L(own).std():.2f}; correlation of log "
          f"with the truth: fit {np.corrcoef(L(fit), L(truth))[0, 1]:.2f} own {np.corrcoef(L(own), L(truth))[0, 1]:.2f}; "
          f"of log own / fit with log truth / fit {np.corrcoef(L(own / fit), L(truth / fit))[0, 1]:.2f}")
    bands = [(-1.0, -0.3), (-0.3, 0.3), (0.3, 0.7), (0.7, 0.99)]

    def band_sums(sources):
        f, o = np.zeros(len(bands)), np.zeros(len(bands))
        for src, S in zip(sources, rows):
            mu = S["dirs"] @ S["n"]
            for i, (lo, hi) in enumerate(bands):
                at = (mu >= lo) & (mu < hi)
                f[i] += sum(grey(src, w) for w in S["dirs"][at])
                o[i] += S["own"][at].sum()
        return " ".join(f"{x:.3f}" for x in f / o)
    print("the pair matched to the face's own source along the normal (target fit + lambda (own - fit)):")
    print(f"  {'family':34s} lambda solved  fit/truth sum median  rms log  fit/own by mu to the normal "
          f"{' '.join(f'[{lo},{hi})' for lo, hi in bands)}")
    print(f"  {'main':34s}   -      -      {fit.sum() / truth.sum():.3f}  {np.median(fit / truth):.3f}   "
          f"{np.sqrt(np.mean(L(fit / truth) ** 2)):.3f}    {band_sums([f[0] for f in fits])}")
    names = list(families(rows[0], fits[0][0], fits[0][1], fits[0][2]))
    for name in names:
        for lam in (1.0, 0.5):
            sources, solved = [], 0
            for S, k, (base, m, fit_info), f in zip(rows, normal, fits, fit):
                target = f + lam * (S["own"][k] - f)
                family = families(S, base, m, fit_info).get(name)
                x = None
                if family:
                    make, lo, hi, near = family

                    def miss(t):
                        src = make(t)
                        return np.nan if src is None else grey(src, S["dirs"][k]) - target
                    x = root(miss, lo, hi, near)
                sources.append(base if x is None else make(x))
                solved += x is not None
            at_n = np.array([grey(src, S["dirs"][k]) for src, S, k in zip(sources, rows, normal)])
            print(f"  {name:34s} {lam:.1f}  {solved:4d}    {at_n.sum() / truth.sum():.3f}  {np.median(at_n / truth):.3f}   "
                  f"{np.sqrt(np.mean(L(at_n / truth) ** 2)):.3f}    {band_sums(sources)}", flush=True)


if __name__ == "__main__":
    main()
