"""Seeded random inputs to firncore (issue 11): triangle soups, NaN/inf, out-of-range and negative indices, empty
arrays, wrong dtypes and shapes, huge counts, absurd settings, corrupted files. Every call must return a valid
result or raise a clear exception; a crash or hang fails the whole test run.

Same seed, same inputs: a failure names its seed, and `pytest -k "fuzz and SEED"` replays it. The C++ driver
(tests/fuzz/fuzz_core.cpp) covers the core itself under the sanitizers (docs/reliability.md, Fuzzing).
"""

import math
import os

import numpy as np
import pytest

import firncore

# What a user may see: ValueError (firncore.BudgetError is one), OSError for files, TypeError when an argument
# is not even the right kind of object (a string where an array belongs: pybind11 refuses the call).
CLEAR = (ValueError, OSError, TypeError)

AWKWARD = [math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 1e-30, 1e-7, 1e7, 1e30, 1e300, -1e30]
SEEDS = range(40)


def awkward(rng):
    return AWKWARD[rng.integers(len(AWKWARD))]


def setting(rng, lo, hi, bad=0.1):
    return awkward(rng) if rng.random() < bad else float(rng.uniform(lo, hi))


def soup(rng, max_triangles=6, scale=1.0):
    """A random triangle soup in awkward clothing: bad values, bad indices, bad dtypes or shapes."""
    n_vertices = int(rng.integers(0, 3 * max_triangles + 1))
    vertices = rng.uniform(-scale, scale, (n_vertices, 3))
    triangles = rng.integers(0, max(n_vertices, 1), (int(rng.integers(0, max_triangles + 1)), 3))
    mangle = rng.integers(12)
    if mangle == 0 and vertices.size:
        vertices.flat[rng.integers(vertices.size)] = awkward(rng)
    elif mangle == 1 and triangles.size:
        triangles.flat[rng.integers(triangles.size)] = rng.choice([-1, n_vertices, 2**31, 2**32 - 1])
    elif mangle == 2:
        vertices = vertices.reshape(-1)  # flat, not (N, 3)
    elif mangle == 3:
        triangles = triangles[:, :2]
    elif mangle == 4:
        vertices = vertices.astype(np.float16)
    elif mangle == 5:
        triangles = triangles.astype(np.float64) + 0.5
    elif mangle == 6:
        vertices = np.array([["a", "b", "c"]] * n_vertices)
    elif mangle == 7:
        vertices, triangles = np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32)
    return vertices, triangles


def ground(rng):
    s = float(rng.uniform(0.1, 0.5))
    vertices = np.array([[-s, -s, 0], [s, -s, 0], [s, s, 0], [-s, s, 0]], np.float32)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], np.uint32)


def snow_settings(rng):
    values = dict(
        depth=setting(rng, 0.03, 0.2),
        spacing=setting(rng, 0.04, 0.2),
        max_slope=setting(rng, 0.2, 1.5),
        randomness=setting(rng, 0, 1),
        smoothness=setting(rng, 0, 1),
        spread=setting(rng, 0, 1),
        exposure_rays=int(rng.choice([1, 2, 4, 0, -3, 10**6])) if rng.random() < 0.2 else 2,
        density_top=setting(rng, 50, 400),
        density_bottom=setting(rng, 100, 917),
        compaction=setting(rng, 0, 1),
        voxel_size=0.0 if rng.random() < 0.7 else setting(rng, 0.005, 0.05),
        max_voxels=float(rng.uniform(1, 1e5)) if rng.random() < 0.9 else awkward(rng),
        seed=int(rng.integers(100)),
    )
    if rng.random() < 0.1:
        values["direction"] = (awkward(rng), awkward(rng), awkward(rng))
    return firncore.SnowLayerSettings(**values)


def check_snow_result(result):
    balls = result["metaballs"]
    n = len(balls["radii"])
    assert balls["centres"].shape == (n, 3) and np.isfinite(balls["centres"]).all()
    assert result["active_voxels"] > 0 and 0.0 <= result["mean_density"] <= firncore.ICE_DENSITY


def call(function, *args, **kwargs):
    """The call's result, or None when it raised a clear exception."""
    try:
        return function(*args, **kwargs)
    except CLEAR as error:
        assert str(error), f"{type(error).__name__} without a message"
        return None


@pytest.mark.parametrize("seed", SEEDS)
def test_fuzz_snow_layer(seed, tmp_path):
    rng = np.random.default_rng(seed)
    path = os.fspath(tmp_path / "snow.vdb")
    targets = ground(rng) if rng.random() < 0.6 else soup(rng)
    occluders = soup(rng, 3) if rng.random() < 0.4 else None
    settings = call(snow_settings, rng)
    if settings is None:
        return
    result = call(firncore.generate_snow_layer, *targets, occluders=occluders, settings=settings, path=path)
    if result is None:
        return
    check_snow_result(result)
    balls = {key: value.copy() for key, value in result["metaballs"].items()}
    for key in rng.choice(sorted(balls), size=int(rng.integers(0, 3))):
        array = balls[key]
        if array.size and rng.random() < 0.7:
            array.flat[rng.integers(array.size)] = awkward(rng)
        else:
            balls[key] = array[: int(rng.integers(0, len(array) + 1))]
    rebuilt = call(firncore.rasterize_metaballs, balls, settings, os.fspath(tmp_path / "again.vdb"))
    if rebuilt is not None:
        check_snow_result(rebuilt)
    budget = int(rng.choice([0, 5, 100, 1000, 150_000]))  # triangles; 5 is refused with a message
    surface = call(firncore.snow_surface_mesh, path, setting(rng, 0, 1), budget)
    if surface is not None:
        vertices, faces = surface
        assert faces.size == 0 or faces.max() < len(vertices)


@pytest.mark.parametrize("seed", SEEDS)
def test_fuzz_grids_and_files(seed, tmp_path):
    rng = np.random.default_rng(seed)
    path = os.fspath(tmp_path / "slab.vdb")
    width = int(rng.choice([1, 2, 3, 0, -4, 10**5])) if rng.random() < 0.3 else int(rng.integers(1, 4))
    layers = int(rng.choice([1, 0, -1, 10**5])) if rng.random() < 0.2 else int(rng.integers(1, 4))
    if call(firncore.write_slab_vdb, path, setting(rng, 0.005, 0.05), width, layers, setting(rng, 0, 500)) is None:
        return
    data = bytearray(open(path, "rb").read())
    if rng.random() < 0.5:
        del data[int(rng.integers(len(data))):]
    for _ in range(int(rng.integers(0, 6))):
        if data:
            data[int(rng.integers(len(data)))] = int(rng.integers(256))
    with open(path, "wb") as file:
        file.write(bytes(data))
    names = call(firncore.grid_names, path)
    if not names:
        return
    points = rng.uniform(-0.1, 0.1, (int(rng.integers(0, 5)), 3))
    if points.size and rng.random() < 0.3:
        points.flat[rng.integers(points.size)] = awkward(rng)
    samples = call(firncore.sample_grid, path, names[0], points)
    if samples is not None:
        assert samples.shape == (len(points),)
    call(firncore.grid_statistics, path, names[0])


@pytest.mark.parametrize("seed", SEEDS)
def test_fuzz_bake(seed, tmp_path):
    rng = np.random.default_rng(seed)
    path = os.fspath(tmp_path / "slab.vdb")
    firncore.write_slab_vdb(path, float(rng.uniform(0.01, 0.03)), int(rng.integers(1, 4)), int(rng.integers(1, 4)),
                            setting(rng, 50, 500, bad=0.0))
    optics = call(firncore.VolumeOptics, setting(rng, 0.5, 10), (setting(rng, 0.9, 1),) * 3, setting(rng, 0, 0.9))
    sun = call(firncore.SunLight, (setting(rng, -1, 1), 0.0, setting(rng, 0.2, 1)), (setting(rng, 0, 3),) * 3,
               setting(rng, 0, 0.1))
    sky_map = rng.uniform(0, 1, (int(rng.integers(0, 3)), int(rng.integers(0, 3)), int(rng.choice([3, 4, 2]))))
    sky = call(firncore.Sky, (setting(rng, 0, 1),) * 3, sky_map if rng.random() < 0.3 else None)
    occluders = []
    if rng.random() < 0.3:
        occluders = [(*soup(rng, 3), (setting(rng, 0, 1),) * 3)]
    if optics is None:
        return
    stats = call(firncore.bake, path, optics, suns=[sun] if sun else [], sky=sky, occluders=occluders,
                 quality=str(rng.choice(["DRAFT", "DRAFT", "FINAL", "nonsense"])), seed=int(rng.integers(10)),
                 sky_samples=int(rng.choice([1, 2, 0, -5, 10**9])), sun_samples=int(rng.choice([1, 0, -1, 10**9])))
    if stats is None:
        return
    origins = rng.uniform(-0.1, 0.1, (int(rng.integers(0, 4)), 3))
    directions = np.tile([0.0, 0.0, -1.0], (len(origins), 1))
    if origins.size and rng.random() < 0.3:
        origins.flat[rng.integers(origins.size)] = awkward(rng)
    radiance = call(firncore.render_baked, path, optics, origins + [0, 0, 1], directions)
    if radiance is not None:
        assert radiance.shape == (len(origins), 3) and np.isfinite(radiance).all()


@pytest.mark.parametrize("seed", SEEDS)
def test_fuzz_optics(seed):
    rng = np.random.default_rng(seed)
    snow = dict(grain_radius=setting(rng, 20e-6, 2e-3), density=setting(rng, 50, 917),
                black_carbon=setting(rng, 0, 1e-6), dust=setting(rng, 0, 1e-4), liquid_water=setting(rng, 0, 0.1),
                B=setting(rng, 1, 2), g=setting(rng, 0.7, 0.9))
    if rng.random() < 0.1:
        snow["ssa"] = setting(rng, 5, 100)
    optics = call(firncore.optics, **snow)
    if optics is not None:
        assert optics.extinction_per_density > 0 and all(0 <= a <= 1 for a in optics.albedo)
        assert all(0 <= a <= 1 for a in optics.white_sky_albedo)
    value = call(firncore.co_albedo, setting(rng, 390e-9, 800e-9), **snow)
    if value is not None:
        assert 0 <= value <= 1
    albedo = call(firncore.kz04_albedo, setting(rng, 390e-9, 800e-9), setting(rng, 0, 1), setting(rng, 0, 1), **snow)
    if albedo is not None:
        assert 0 <= albedo <= 1


@pytest.mark.parametrize("seed", SEEDS)
def test_fuzz_grains(seed):
    rng = np.random.default_rng(seed)
    vertices, triangles = soup(rng) if rng.random() < 0.5 else ground(rng)
    direction = (awkward(rng), awkward(rng), awkward(rng)) if rng.random() < 0.1 else (0, 0, -1)
    count = int(rng.choice([0, 1, 50, 200, 10**9])) if rng.random() < 0.2 else 100
    grains = call(firncore.accumulate_grains, vertices, triangles, count=count, radius=setting(rng, 2e-3, 2e-2),
                  radius_variation=setting(rng, 0, 0.9), direction=direction, max_slope_deg=setting(rng, 0, 90),
                  seed=int(rng.integers(100)), max_rays=2000)
    if grains is not None:
        centres, radii, stats = grains
        assert centres.shape == (len(radii), 3) and np.isfinite(centres).all() and (radii > 0).all()
        assert stats["rays"] <= 2000
    n = int(rng.integers(0, 20))
    centres = rng.uniform(-0.1, 0.1, (n, 3))
    radii = rng.uniform(1e-3, 2e-2, n)
    if n and rng.random() < 0.3:
        (centres.flat if rng.random() < 0.5 else radii)[0] = awkward(rng)
    origins = rng.uniform(-0.3, 0.3, (4, 3))
    directions = rng.normal(size=(4, 3)) if rng.random() < 0.9 else np.zeros((4, 3))
    result = call(firncore.grain_radiance, centres, radii, origins, directions, eta=setting(rng, 1.2, 1.5),
                  ice_absorption=(setting(rng, 0, 100),) * 3, sky=(setting(rng, 0, 2),) * 3,
                  samples=int(rng.choice([1, 4, 0, -1])) if rng.random() < 0.2 else 4, seed=seed)
    if result is not None:
        mean, error = result
        assert mean.shape == (4, 3) and np.isfinite(mean).all() and (mean >= 0).all()
