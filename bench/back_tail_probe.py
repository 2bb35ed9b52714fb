"""What one Henyey-Greenstein lobe can show of the air across a flat snow face (branch back-tail, docs/benchmarks.md
"back-tail").

A face's stored lobe (mean 1, anisotropy k_face about its normal n; exitLobe's escape-shaped fit is k 0.24) and the
in-scatter of its exit radiance in the ramp, J(w) = integral over n . w' > 0 of L(w') HG(g, w . w') dw' (albedo 1;
Gauss-Legendre nodes, 48 x 96 on the hemisphere, 32 x 64 on the sphere). Printed at cosines n . w: J, the face's lobe
(what the air shows on main), and the lobes fitted by least squares in radiance over the sphere to two targets: J
everywhere (bench/back_tail_switch.diff's rampLobe: J's mean kept, k fitted) and the face's lobe in front with J
behind (what a camera in front, seeing the face through the ramp, and one behind, seeing the air past an edge, need).

    /usr/bin/python3 bench/back_tail_probe.py [--k-face 0.24] [--g 0.7]
"""

import argparse

import numpy as np


def lobe(k, c):  # 4 pi HG(k, c): mean 1 over the sphere
    d = 1.0 + k * k - 2.0 * k * c
    return (1.0 - k * k) / (d * np.sqrt(d))


def directions(mu, mu_weights, n_phi):
    phi = (np.arange(n_phi) + 0.5) * 2.0 * np.pi / n_phi
    m, p = np.meshgrid(mu, phi, indexing="ij")
    s = np.sqrt(1.0 - m * m)
    w = np.stack([s * np.cos(p), s * np.sin(p), m], -1).reshape(-1, 3)
    return w, (mu_weights[:, None] * np.full(n_phi, 2.0 * np.pi / n_phi)[None, :]).reshape(-1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--k-face", type=float, default=0.24)
    parser.add_argument("--g", type=float, default=0.7)
    a = parser.parse_args()
    mu, wm = np.polynomial.legendre.leggauss(48)
    hemi, hemi_w = directions(0.5 * (mu + 1.0), 0.5 * wm, 96)
    mu, wm = np.polynomial.legendre.leggauss(32)
    sphere, sphere_w = directions(mu, wm, 64)

    def in_scatter(w):
        return (lobe(a.g, w @ hemi.T) / (4.0 * np.pi) * (lobe(a.k_face, hemi[:, 2]) * hemi_w)[None, :]).sum(1)

    J = in_scatter(sphere)
    J_mean = (J * sphere_w).sum() / (4.0 * np.pi)
    front_back = np.where(sphere[:, 2] >= 0.0, lobe(a.k_face, sphere[:, 2]), J)
    ks = np.arange(0.0, 0.951, 0.01)

    def fit(target, mean=None):  # least squares in radiance over the sphere; the mean kept where given
        best = None
        for k in ks:
            h = lobe(k, sphere[:, 2])
            scale = mean if mean is not None else (sphere_w * h * target).sum() / (sphere_w * h * h).sum()
            error = (sphere_w * (scale * h - target) ** 2).sum()
            if best is None or error < best[0]:
                best = (error, k, scale)
        return best[1], best[2]

    k_J, l0_J = fit(J, J_mean)
    k_fb, l0_fb = fit(front_back)
    cosines = np.array([-1.0, -0.707, -0.5, 0.0, 0.5, 0.707, 1.0])
    w = np.stack([np.sqrt(1.0 - cosines**2), 0.0 * cosines, cosines], -1)
    print(f"face lobe k {a.k_face}, g {a.g}: J's mean {J_mean:.3f} of the face lobe's l0 (its hemisphere's share)")
    print(f"fit to J (mean kept): k {k_J:.2f}, l0 {l0_J:.3f};  fit to face-front / J-back: k {k_fb:.2f}, l0 {l0_fb:.3f}")
    print("   n.w        J   face lobe (main)   fit to J   fit to front/back")
    for c, j, row in zip(cosines, in_scatter(w), w):
        print(f"{c:+7.3f} {j:8.3f} {lobe(a.k_face, c):12.3f} {l0_J * lobe(k_J, c):14.3f} {l0_fb * lobe(k_fb, c):14.3f}")


if __name__ == "__main__":
    main()
