"""The truth's light in a ball's skin along the sun's great circle: fluence, net flux and Fick's law's flux.

At the angle theta from the sub-solar point (over the top, in the sun's vertical plane) and at the depths of the
outer voxel's node (r = R - h/2) and the one beneath (R - 3h/2), the core's Monte Carlo gives the fluence
phi = 4 pi <L> and the net flux F = -(4 pi / N) sum L(w) w over a Fibonacci sphere of directions w (L the scattered
radiance arriving from w; the uncollided sun left out). Fick's law's flux is -D grad phi, D = 1 / (3 sigma_t'),
sigma_t' = (1 - omega g) sigma_t as the bake's diffusion takes it: along the surface from phi at theta -+ dtheta,
along the normal from the two depths. The ratio F / Fick says how far the skin's light is from diffusion: 1 where it
diffuses. The bake's beam is attenuated with sigma_t' (docs/bake.md, Method 2: forward-scattered light travels on
with the beam), so the light scattered forwards that the beam carries, (e^-tau' - e^-tau) along the sun's travel, is
no part of what its diffusion must carry: "diffuse" subtracts it from phi and F before the ratio. kappa L: the outer
node's e-fold rate along the surface, -d ln phi / ds, times the diffusion length 1 / sqrt(3 sigma_a sigma_t'): 1 where
the skin's light falls along the surface as a bulk diffusion mode does (absorption alone). The sun alone, green
channel, W/m^2 per W/m^2 of sun. docs/benchmarks.md, limb-skin.

    PYTHONPATH=build/python python3 bench/skin_flux.py [--cases ball_issue,ball_grey,ball_forward,ball_snow]
        [--thetas 60,75,85,90,95,100,105,110,120] [--dtheta 5] [--samples 64] [--sphere 48]
"""

import argparse
import math
import os
import tempfile

import numpy as np

import bake_suite
import firncore
from backlit_probe import sun_towards
from limb_circle import fibonacci


def snow_quantities(case):
    """sigma_t h, omega, g, sigma_t' h, and the diffusion length 1 / sqrt(3 sigma_a sigma_t') per voxel (green)."""
    sigma_t, omega, g, h = case.sigma_t, case.omega[1], case.g, case.voxel
    reduced = (1 - omega * g) * sigma_t
    length_m = 1 / math.sqrt(3 * (1 - omega) * sigma_t * reduced)
    return sigma_t * h, omega, g, reduced * h, length_m / h


def forward_beam(case, points, step=0.0005):
    """The similarity's forward-scattered sun at each point (W/m^2 per W/m^2): e^-tau' - e^-tau along the sun."""
    sun, k, omega, g = sun_towards(), case.sigma_t / case.rho, case.omega[1], case.g
    s = np.arange(step / 2, 0.4, step)
    out = []
    for p in points:
        tau = k * bake_suite.trilinear(case.density, (p + s[:, None] * sun) / case.voxel).sum() * step
        out.append(math.exp(-(1 - omega * g) * tau) - math.exp(-tau))
    return np.array(out)


def skin_light(case, path, thetas_deg, radii_m, sphere, samples):
    """phi (theta, radius) and F's normal and tangential parts (theta, radius), each with its standard error."""
    centre = (np.array(case.density.shape) - 1) / 2 * case.voxel
    sun = sun_towards()
    up_circle = np.array([-sun[2], 0.0, sun[0]])  # in the sun's vertical plane, towards the zenith side
    origins, directions, points = [], [], []
    for theta in np.radians(thetas_deg):
        normal = math.cos(theta) * sun + math.sin(theta) * up_circle
        for r in radii_m:
            origins += [centre + r * normal] * len(sphere)
            directions += list(sphere)
            points.append(centre + r * normal)
    L, err = firncore.monte_carlo_radiance(path, case.optics, np.array(origins), np.array(directions),
                                           suns=case.suns(), samples=samples, seed=7)
    shape = (len(thetas_deg), len(radii_m), len(sphere))
    L, err = L[:, 1].reshape(shape), err[:, 1].reshape(shape)
    weight = 4 * math.pi / len(sphere)
    phi = weight * L.sum(2)
    phi_err = weight * np.sqrt((err ** 2).sum(2))
    beam = forward_beam(case, points).reshape(shape[:2])
    normal_flux, tangential_flux = np.zeros(shape[:2]), np.zeros(shape[:2])
    normal_err, tangential_err = np.zeros(shape[:2]), np.zeros(shape[:2])
    for i, theta in enumerate(np.radians(thetas_deg)):
        normal = math.cos(theta) * sun + math.sin(theta) * up_circle
        tangent = -math.sin(theta) * sun + math.cos(theta) * up_circle  # towards larger theta
        for k in range(len(radii_m)):
            for axis, flux, flux_err in ((normal, normal_flux, normal_err), (tangent, tangential_flux,
                                                                            tangential_err)):
                w = sphere @ axis
                flux[i, k] = -weight * (L[i, k] * w).sum()
                flux_err[i, k] = weight * math.sqrt(((err[i, k] * w) ** 2).sum())
                flux[i, k] -= beam[i, k] * float(-sun @ axis)  # the beam's share, along the sun's travel
    return phi - beam, phi_err, normal_flux, normal_err, tangential_flux, tangential_err, beam


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", default="ball_issue,ball_grey,ball_forward,ball_snow")
    parser.add_argument("--thetas", default="60,75,85,90,95,100,105,110,120", help="degrees from the sub-solar point")
    parser.add_argument("--dtheta", type=float, default=5.0, help="degrees either side for Fick's gradient")
    parser.add_argument("--samples", type=int, default=64, help="Monte Carlo paths per direction")
    parser.add_argument("--sphere", type=int, default=48, help="directions per point")
    args = parser.parse_args()

    centres = [float(x) for x in args.thetas.split(",")]
    thetas = sorted({round(t + s * args.dtheta, 6) for t in centres for s in (-1, 0, 1)})
    sphere = fibonacci(args.sphere)
    for name in args.cases.split(","):
        case = bake_suite.case(name)
        tau, omega, g, reduced, length_voxels = snow_quantities(case)
        # the antialiased ball's filled volume is the sphere's
        radius = (3 / (4 * math.pi) * case.density.sum() / case.density.max()) ** (1 / 3) * case.voxel
        h = case.voxel
        radii = [radius - h / 2, radius - 3 * h / 2]
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "snow.vdb")
            bake_suite.write_density(path, case.density, case.voxel)
            phi, phi_err, Fn, Fn_err, Ft, Ft_err, beam = skin_light(case, path, thetas, radii, sphere, args.samples)
        D = h / (3 * reduced)  # m: 1 / (3 sigma_t')
        print(f"{name}: sigma_t h {tau:.1f}, omega {omega}, g {g}, sigma_t' h {reduced:.2f} (1/sigma_t' "
              f"{100 * h / reduced:.2f} cm), diffusion length {length_voxels:.2f} h; R {100 * radius:.1f} cm; "
              f"{args.sphere} x {args.samples} paths per point")
        print("diffuse: the Monte Carlo less the beam's forward part (its phi at the outer node in [])")
        print("theta  outer node (R - h/2): phi (+-)       F_t (+-)          Fick_t   F_t/Fick  F_n (+-)          "
              "|  node beneath: phi      F_t      Fick_t   F_t/Fick | phi out/in  Fick_n(out)  F_n/Fick_n  kappa L")
        for t in centres:
            i = thetas.index(t)
            lo, hi = thetas.index(round(t - args.dtheta, 6)), thetas.index(round(t + args.dtheta, 6))
            row = f"{t:5.0f}"
            for k in range(2):
                arc = radii[k] * math.radians(2 * args.dtheta)
                fick = -D * (phi[hi, k] - phi[lo, k]) / arc
                if k == 0:
                    row += (f"  {phi[i, k]:.4f} ({phi_err[i, k]:.4f}) [{beam[i, k]:.3f}]  "
                            f"{Ft[i, k]:+.4f} ({Ft_err[i, k]:.4f})  {fick:+.4f}  {Ft[i, k] / fick:6.2f}   "
                            f"{Fn[i, k]:+.4f} ({Fn_err[i, k]:.4f})  |")
                else:
                    row += f"  {phi[i, k]:.4f}  {Ft[i, k]:+.4f}  {fick:+.4f}  {Ft[i, k] / fick:6.2f} |"
            fick_n = -D * (phi[i, 0] - phi[i, 1]) / h
            kappa = -math.log(phi[hi, 0] / phi[lo, 0]) / (radii[0] * math.radians(2 * args.dtheta))  # 1/m
            row += (f"  {phi[i, 0] / phi[i, 1]:.2f}  {fick_n:+.4f}  {Fn[i, 0] / fick_n:6.2f}  "
                    f"{kappa * length_voxels * h:6.2f}")
            print(row)


if __name__ == "__main__":
    main()
