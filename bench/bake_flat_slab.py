"""The fraction of a sun's flux a flat slab of absorbing snow returns: the bake against the half-space's (docs/bake.md,
Accuracy: the shadowed side).

A wide flat slab (64 x 64 voxels of 1 cm, 6 deep: a half-space for these optical depths) baked under a sun alone at
90 and 30 degrees elevation; its baked radiance (`firncore.render_baked`, channel G) integrated over the hemisphere
about the top's centre (Gauss-Legendre in the cosine, 6 nodes, 12 azimuths) against the core's 1D Monte Carlo of
the half-space (`firncore.slab_monte_carlo`, tau inf).

    PYTHONPATH=build/python /usr/bin/python3 bench/bake_flat_slab.py
"""

import math
import os
import sys
import tempfile

import numpy as np

import firncore

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bake_suite  # noqa: E402

SNOWS = [(0.9, 0.6, 5.0), (0.98, 0.85, 10.0)]  # omega, g, optical depth per voxel
ELEVATIONS = (90.0, 30.0)  # degrees


def baked_albedo(folder, omega, g, tau_per_voxel, elevation, width=64, layers=6):
    """The baked slab's exitance over the sun's irradiance on it."""
    density = bake_suite.slab(width, layers) * 100.0
    optics = firncore.VolumeOptics(tau_per_voxel / 0.01 / 100.0, (omega,) * 3, g)
    e = math.radians(elevation)
    sun = firncore.SunLight((math.cos(e), 0.0, math.sin(e)), (1.0,) * 3, 0.0093)
    path = os.path.join(folder, "flat_slab.vdb")
    bake_suite.write_density(path, density, 0.01)
    firncore.bake(path, optics, suns=[sun], seed=0)
    top = np.array([(density.shape[0] - 1) / 2, (density.shape[1] - 1) / 2, 2 + layers - 0.5]) * 0.01
    nodes, weights = np.polynomial.legendre.leggauss(6)
    origins, directions, projected = [], [], []
    for mu, w in zip(0.5 * (nodes + 1.0), 0.5 * weights):
        for k in range(12):
            phi, s = 2.0 * math.pi * (k + 0.5) / 12, math.sqrt(1.0 - mu * mu)
            back = np.array([s * math.cos(phi), s * math.sin(phi), mu])
            origins.append(top + 2.0 * back), directions.append(-back), projected.append(w * mu * 2.0 * math.pi / 12)
    radiance = firncore.render_baked(path, optics, np.array(origins), np.array(directions))[:, 1]
    return float(np.dot(projected, radiance)) / math.sin(e)


def half_space_albedo(omega, g, elevation, photons=200000):
    r = firncore.slab_monte_carlo(omega=omega, g=g, tau=float("inf"), mu0=math.sin(math.radians(elevation)),
                                  photons=photons, seed=3)
    return r["reflectance"], r["reflectance_error"]


def main():
    with tempfile.TemporaryDirectory() as folder:
        for omega, g, tau in SNOWS:
            for elevation in ELEVATIONS:
                exact, error = half_space_albedo(omega, g, elevation)
                baked = baked_albedo(folder, omega, g, tau, elevation)
                print(f"omega {omega} g {g} (tau {tau:g}/voxel) sun {elevation:g} deg: baked {baked:.4f}, half-space "
                      f"{exact:.4f} +- {error:.4f}, bias {100 * (baked / exact - 1):+.1f} %", flush=True)


if __name__ == "__main__":
    main()
