"""Grain snow through the Python API (issue 12): accumulation, the grain renderer and the pile albedo.

Oracles: the geometry of the scene (no grain below the ground, none pressed into another beyond the stated
tolerance), determinism, and light on one sphere seen along its axis: L = R + (1 - R)^2 T / (1 - R T),
R = ((n - 1) / (n + 1))^2, T = exp(-2 gamma r) (Fresnel at normal incidence, Born & Wolf 1.5.3)."""

import math

import numpy as np
import pytest

import firncore
from conftest import cancelled_while_running


def plane(size=0.1, z=0.0):
    h = size / 2
    vertices = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]], np.float32)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], np.uint32)


def test_grains_rest_on_the_ground_without_overlap():
    centres, radii, stats = firncore.accumulate_grains(*plane(), count=800, radius=2e-3, radius_variation=0.2, seed=3)
    assert centres.shape == (800, 3) and centres.dtype == np.float64 and radii.shape == (800,)
    assert np.all(centres[:, 2] >= radii * (1 - firncore.GRAIN_OVERLAP_TOLERANCE) - 1e-9)
    assert np.all((radii >= 1.6e-3 - 1e-12) & (radii <= 2.4e-3 + 1e-12))
    gaps = np.linalg.norm(centres[:, None, :] - centres[None, :, :], axis=2) - (radii[:, None] + radii[None, :])
    np.fill_diagonal(gaps, np.inf)
    smaller = np.minimum(radii[:, None], radii[None, :])
    assert np.all(gaps >= -firncore.GRAIN_OVERLAP_TOLERANCE * smaller - 1e-12)
    assert stats["rays"] == 800 + stats["missed"] + stats["steep"] + stats["overlapping"]


def test_same_seed_same_grains():
    a = firncore.accumulate_grains(*plane(), count=500, radius=1e-3, seed=8)
    b = firncore.accumulate_grains(*plane(), count=500, radius=1e-3, seed=8)
    c = firncore.accumulate_grains(*plane(), count=500, radius=1e-3, seed=9)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])


def test_steep_ground_gets_no_grains():
    vertices, triangles = plane()
    tilt = math.radians(70)
    vertices[:, 2] = vertices[:, 1] * math.tan(tilt)
    centres, radii, stats = firncore.accumulate_grains(vertices, triangles, count=50, radius=1e-3, max_rays=500)
    assert len(radii) == 0 and stats["steep"] > 0
    assert len(firncore.accumulate_grains(vertices, triangles, count=50, radius=1e-3, max_slope_deg=75)[1]) == 50


def test_one_sphere_seen_along_its_axis():
    gamma, r, n = 300.0, 1e-3, 1.31
    mean, error = firncore.grain_radiance([[0, 0, 0]], [r], [[0, 0, 1]], [[0, 0, -1]], ice_absorption=(0, gamma, 0),
                                          samples=20000, seed=2)
    R, T = ((n - 1) / (n + 1)) ** 2, math.exp(-2 * gamma * r)
    expected = [1.0, R + (1 - R) ** 2 * T / (1 - R * T), 1.0]  # no absorption: the sky's radiance 1
    assert mean.shape == (1, 3) and error.shape == (1, 3)
    assert np.all(np.abs(mean[0] - expected) <= 4 * error[0] + 1e-12)


def test_pile_albedo_is_one_without_absorption_over_white_ground():
    d = firncore.grain_pile_albedo(radius=1e-3, width=12e-3, depth=20e-3, ice_absorption=(0, 0, 0),
                                   ground_albedo=(1, 1, 1), paths=500, seed=1)
    assert d["albedo"] == pytest.approx([1.0, 1.0, 1.0], abs=1e-9)
    assert d["bailed_out"] == 0 and 0.15 < d["volume_fraction"] < 0.64
    assert d["density"] == pytest.approx(917 * d["volume_fraction"])


def test_releases_the_gil_and_cancels():
    progress = firncore.Progress()
    assert cancelled_while_running(
        lambda: firncore.accumulate_grains(*plane(1.0), count=2_000_000, radius=1e-3, progress=progress), progress)


@pytest.mark.parametrize("kwargs, error", [
    (dict(count=0, radius=1e-3), ValueError),
    (dict(count=10, radius=-1.0), ValueError),
    (dict(count=10, radius=math.nan), ValueError),
    (dict(count=10, radius=1e-12), ValueError),   # below float precision at the scene's size
    (dict(count=10, radius=1e-3, radius_variation=1.0), ValueError),
    (dict(count=10, radius=1e-3, direction=(0, 0, 0)), ValueError),
    (dict(count=10, radius=1e-3, max_slope_deg=120), ValueError),
    (dict(count=10**9, radius=1e-3), firncore.BudgetError),
])
def test_bad_accumulation_input(kwargs, error):
    with pytest.raises(error):
        firncore.accumulate_grains(*plane(), **kwargs)


def test_bad_render_input():
    with pytest.raises(ValueError):
        firncore.grain_radiance([[0, 0, 0]], [-1.0], [[0, 0, 1]], [[0, 0, -1]])
    with pytest.raises(ValueError):
        firncore.grain_radiance([[0, 0, 0]], [1.0, 2.0], [[0, 0, 1]], [[0, 0, -1]])
    with pytest.raises(ValueError):
        firncore.grain_radiance([[0, 0, 0]], [1.0], [[0, 0, 1]], [[0, 0, -1]], eta=0.9)
    with pytest.raises(ValueError):
        firncore.grain_pile_albedo(radius=1e-3, width=1e-3, depth=1e-2)
    with pytest.raises(ValueError):
        firncore.grain_pile_albedo(radius=1e-3, width=1e-2, depth=1e-2, illumination="SUN")
