"""The moment fit's lobe pair under path noise (docs/benchmarks.md, lobe-noise): reads the LNFIT lines that
bench/lobe_noise_hooks.diff prints (FIRN_LN_PRINT=1; one per tracedSourceByMoments call: voxel, face (0: the
voxel's own fit), whether Prony's pair holds, a0, a_n / a0 for n = 1..3, the beams' share of a0) from bakes at
256 paths (several seeds, each after a "SEED s" line) and one at 2048 (FIRN_LN_PATHS=2048), and compares, per fit
kind, the broad lobe's first moment along the beams' axis and the peak's weight (a0-weighted means, in units of a0)
split by whether the 256-path fit held, with the same fits at 2048; then the same with the pair's nodes fitted to
the moments summed over the fits within one voxel (the hooks' FIRN_LN_POOL / FIRN_LN_FPOOL).

    python3 bench/lobe_noise_fits.py fits256.txt fits2048.txt
"""

import sys

import numpy as np

K_MAX = 0.95  # kMaxLobeAnisotropy
K_BEAM = 0.85  # crossingAnisotropy(g) at spray_dense's g: the failed fit's peak


def load(path):
    """Per bake, {(x, y, z, face): (held, a0, mu1, mu2, mu3, beam share)}."""
    runs = []
    for line in open(path):
        p = line.split()
        if p[0] == "SEED":
            runs.append({})
        elif p[0] == "LNFIT" and len(p) >= 11:
            if not runs:
                runs.append({})
            runs[-1][tuple(map(int, p[1:5]))] = (int(p[5]),) + tuple(map(float, p[6:11]))
    return runs


def prony(a0, a1, a2, a3):
    """The pair's nodes (kPeak, kBroad) as traced_source.cpp's lobePair finds them, or None."""
    det = a1 * a1 - a0 * a2
    if not abs(det) > 1e-9 * a0 * a0:
        return None
    c1, c0 = (a0 * a3 - a1 * a2) / det, (a2 * a2 - a1 * a3) / det
    disc = c1 * c1 - 4.0 * c0
    if not disc >= 0.0:
        return None
    x1, x2 = 0.5 * (-c1 + disc ** 0.5), 0.5 * (-c1 - disc ** 0.5)
    if not (x1 > x2 and x1 <= 1.0 and x2 >= -K_MAX):
        return None
    w1 = (a1 - x2 * a0) / (x1 - x2)
    return (x1, x2) if 0.0 <= w1 <= a0 else None


def split(fit, nodes):
    """(broad first moment, peak weight) in units of a0: the pair's, else the beams' single scattering as the peak."""
    _, _, mu1, _, _, beam = fit
    if nodes is None:
        return mu1 - K_BEAM * beam, beam
    kp, kb = nodes
    w = min(max((mu1 - kb) / (kp - kb), 0.0), 1.0)
    return mu1 - min(kp, K_MAX) * w, w


def pooled_nodes(run, key):
    """The nodes of the moments summed over the fits of the same kind (voxel or face) within one voxel."""
    s = np.zeros(4)
    for other, fit in run.items():
        if (other[3] == 0) == (key[3] == 0) and max(abs(other[i] - key[i]) for i in range(3)) <= 1:
            s += fit[1] * np.array([1.0, fit[2], fit[3], fit[4]])
    return prony(*s)


def mean_split(run, keys, pooled):
    a0 = b1 = w = 0.0
    for k in keys:
        fit = run[k]
        nodes = pooled_nodes(run, k) if pooled else prony(1.0, *fit[2:5])
        b, p = split(fit, nodes)
        a0, b1, w = a0 + fit[1], b1 + fit[1] * b, w + fit[1] * p
    return (b1 / a0, w / a0) if a0 > 0.0 else (float("nan"), float("nan"))


def main():
    low, high = load(sys.argv[1]), load(sys.argv[2])[0]
    fails = [sum(1 - f[0] for f in r.values()) for r in low]
    print(f"fits per bake at 256: {[len(r) for r in low]}, Prony fails {fails}; at 2048 {len(high)}, fails "
          f"{sum(1 - f[0] for f in high.values())}")
    for kind, is_kind in (("voxels", lambda k: k[3] == 0), ("faces", lambda k: k[3] > 0)):
        print(f"{kind}: broad first moment / peak weight (units of a0)")
        for held in (1, 0):
            own = np.mean([mean_split(r, [k for k in r if is_kind(k) and k in high and r[k][0] == held], False)
                           for r in low], axis=0)
            same = np.mean([mean_split(high, [k for k in r if is_kind(k) and k in high and r[k][0] == held], False)
                            for r in low], axis=0)
            print(f"  Prony {'holds' if held else 'fails'} at 256: 256 {own[0]:.4f} / {own[1]:.3f}, "
                  f"the same fits at 2048 {same[0]:.4f} / {same[1]:.3f}")
        keys = [k for k in high if is_kind(k)]
        for pooled in (False, True):
            at256 = np.mean([mean_split(r, [k for k in keys if k in r], pooled) for r in low], axis=0)
            at2048 = mean_split(high, keys, pooled)
            print(f"  {'pooled nodes' if pooled else 'own fit     '}: 256 {at256[0]:.4f} / {at256[1]:.3f}, "
                  f"2048 {at2048[0]:.4f} / {at2048[1]:.3f}")


if __name__ == "__main__":
    main()
