"""Bake Scattering through the Python API, without Blender.

Oracles: the exact semi-infinite plane albedo A(mu) (adding-doubling / Chandrasekhar H-functions, table in
/work/shared/notes/snow-optics.md) and energy conservation."""

import math
import os

import numpy as np
import pytest

import firncore
from conftest import cancelled_while_running

# g 0.87, omega 0.9999: A(1) = 0.92182, A(0.5) = 0.94594 (notes' exact table).
EXACT_A1 = 0.92182
SNOW = firncore.VolumeOptics(5000.0 / 300.0, (0.9999, 0.9999, 0.9999), 0.87)  # sigma_t 5000 /m at 300 kg/m^3


@pytest.fixture
def slab(tmp_vdb):
    firncore.write_slab_vdb(tmp_vdb, voxel_size=0.01, width=32, layers=30, density=300.0)
    return tmp_vdb


def grid_names(path):
    import pyopenvdb

    return sorted(grid.name for grid in pyopenvdb.readAll(path)[0])


def down(points):
    """Camera rays from 0.5 m above each (x, y) point, looking straight down."""
    origins = np.array([[x, y, 0.5] for x, y in points], dtype=float)
    return origins, np.tile([0.0, 0.0, -1.0], (len(points), 1))


def test_bake_adds_the_contract_grids(slab):
    stats = firncore.bake(slab, SNOW, sky=firncore.Sky((1.0, 1.0, 1.0)), quality="DRAFT")
    assert grid_names(slab) == sorted(("density",) + firncore.BAKED_GRID_NAMES)
    assert stats["unknowns"] == 32 * 32 * 30
    assert stats["surface_voxels"] > 32 * 32
    firncore.bake(slab, SNOW, sky=firncore.Sky((1.0, 1.0, 1.0)), quality="DRAFT")  # again: replaced, not doubled
    assert grid_names(slab) == sorted(("density",) + firncore.BAKED_GRID_NAMES)


def test_slab_under_white_sky_shows_exact_albedo(slab):
    # By reciprocity A(mu) is the radiance seen at cos(view) mu under a uniform sky of unit radiance.
    firncore.bake(slab, SNOW, sky=firncore.Sky((1.0, 1.0, 1.0)))
    radiance = firncore.render_baked(slab, SNOW, *down([(0.0, 0.0)]))
    assert radiance[0] == pytest.approx([EXACT_A1] * 3, rel=0.01)


def test_monte_carlo_reference_shows_exact_albedo(slab):
    mean, error = firncore.monte_carlo_radiance(
        slab, SNOW, *down([(0.0, 0.0)]), sky=firncore.Sky((1.0, 1.0, 1.0)), samples=3000, seed=1)
    assert abs(mean[0, 1] - EXACT_A1) < 4.0 * error[0, 1] + 0.002  # the slab's finite width: 0.2 %


def test_half_space_helpers_match_exact_table():
    r = firncore.slab_monte_carlo(omega=0.999, g=0.0, tau=float("inf"), mu0=0.5, photons=40000, seed=2)
    assert abs(r["reflectance"] - 0.93806) < 4.0 * r["reflectance_error"]
    conservative = firncore.slab_monte_carlo(omega=1.0, g=0.85, tau=5.0, mu0=1.0, photons=5000)
    assert conservative["reflectance"] + conservative["transmittance"] == pytest.approx(1.0)
    assert firncore.art_plane_albedo(0.9999, 0.87, 1.0) == pytest.approx(EXACT_A1, rel=0.005)
    assert firncore.art_spherical_albedo(0.999, 0.0) == pytest.approx(0.92971, rel=0.005)


def test_reference_quality_path_traces_the_surface(tmp_vdb):
    # REFERENCE replaces the surface's radiance by Monte Carlo: under a white sky it too shows A(1)
    # (g 0, omega 0.999: exact 0.91285). 32 paths in each of 12 directions per voxel: ~2 % noise.
    optics = firncore.VolumeOptics(2000.0 / 300.0, (0.999, 0.999, 0.999), 0.0)
    firncore.write_slab_vdb(tmp_vdb, voxel_size=0.01, width=8, layers=8, density=300.0)
    firncore.bake(tmp_vdb, optics, sky=firncore.Sky(), quality="REFERENCE", reference_samples=32, seed=4)
    radiance = firncore.render_baked(tmp_vdb, optics, *down([(0.0, 0.0)]))[0, 1]
    assert radiance == pytest.approx(0.91285, rel=0.06)


def test_sun_irradiance_and_colour_scale_the_result(slab):
    sun = firncore.SunLight(direction=(0.0, 0.3, 1.0), irradiance=(1.0, 2.0, 4.0), angular_diameter=0.0093)
    firncore.bake(slab, SNOW, suns=[sun], quality="DRAFT")
    r, g, b = firncore.render_baked(slab, SNOW, *down([(0.0, 0.0)]))[0]
    assert g == pytest.approx(2.0 * r, rel=1e-3) and b == pytest.approx(4.0 * r, rel=1e-3)
    assert 0.2 < r < 0.35  # a white snow, mu0 0.96: about A mu0 / pi


def test_occluder_casts_a_shadow(slab):
    plate = (np.array([[-0.2, -0.2, 0.3], [0.0, -0.2, 0.3], [0.0, 0.2, 0.3], [-0.2, 0.2, 0.3]], dtype=np.float32),
             np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32), (0.0, 0.0, 0.0))
    sun = firncore.SunLight((0.0, 0.0, 1.0), (1.0, 1.0, 1.0))
    firncore.bake(slab, SNOW, suns=[sun], occluders=[plate], quality="DRAFT")
    shade, light = firncore.render_baked(slab, SNOW, *down([(-0.1, 0.0), (0.1, 0.0)]))[:, 0]
    assert shade < 0.3 * light


def test_sky_map_in_blenders_convention(slab):
    # Only the upper half of the map is lit: the slab's top sees exactly what a uniform sky gives it.
    pixels = np.zeros((8, 16, 4), dtype=np.float32)
    pixels[4:, :, :3] = 1.0
    firncore.bake(slab, SNOW, sky=firncore.Sky((1.0, 1.0, 1.0), pixels), quality="DRAFT")
    top = firncore.render_baked(slab, SNOW, *down([(0.0, 0.0)]))[0, 0]
    assert top == pytest.approx(EXACT_A1, rel=0.02)
    sky = firncore.Sky((0.5, 0.5, 0.5), pixels)
    assert sky.radiance_from((0.0, 0.0, 1.0))[0] == pytest.approx(0.5)
    assert sky.radiance_from((0.0, 0.0, -1.0))[0] == pytest.approx(0.0)


def test_progress_is_reported(slab):
    seen = []
    progress = firncore.Progress(lambda fraction, stage: seen.append((fraction, stage)))
    firncore.bake(slab, SNOW, sky=firncore.Sky(), quality="DRAFT", progress=progress)
    assert progress.fraction == 1.0
    assert seen[-1][0] == 1.0
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))


def test_cancel_raises_and_leaves_the_file(slab):
    before = os.path.getmtime(slab), grid_names(slab)
    progress = firncore.Progress()
    progress.cancel()
    with pytest.raises(firncore.Cancelled):
        firncore.bake(slab, SNOW, sky=firncore.Sky(), progress=progress)
    assert (os.path.getmtime(slab), grid_names(slab)) == before


def test_cancel_while_light_and_thin_snow_are_traced_leaves_the_file(slab):
    """Cancelled from the callback as the sun and sky light and the thin snow start to be traced side by side (a
    new stage always reaches the callback): the bake raises firncore.Cancelled from within them and writes nothing."""
    before = os.path.getmtime(slab), grid_names(slab)
    stages = []

    def cancel_there(fraction, stage):
        stages.append(stage)
        if stage == "Tracing sun and sky light, and thin snow":
            progress.cancel()

    progress = firncore.Progress(cancel_there)
    with pytest.raises(firncore.Cancelled):
        firncore.bake(slab, SNOW, sky=firncore.Sky(), quality="DRAFT", progress=progress)
    assert stages[-1] == "Tracing sun and sky light, and thin snow"
    assert (os.path.getmtime(slab), grid_names(slab)) == before


def test_bake_releases_the_gil(tmp_vdb):
    firncore.write_slab_vdb(tmp_vdb, voxel_size=0.01, width=96, layers=32, density=300.0)
    before = os.path.getmtime(tmp_vdb), grid_names(tmp_vdb)
    progress = firncore.Progress()
    assert cancelled_while_running(lambda: firncore.bake(tmp_vdb, SNOW, sky=firncore.Sky(), progress=progress),
                                   progress)
    assert (os.path.getmtime(tmp_vdb), grid_names(tmp_vdb)) == before


def test_same_seed_same_file(slab, tmp_path):
    other = os.fspath(tmp_path / "other.vdb")
    firncore.write_slab_vdb(other, voxel_size=0.01, width=32, layers=30, density=300.0)
    sun = firncore.SunLight((0.2, 0.1, 1.0), (1.0, 1.0, 1.0), 0.0093)
    for path in (slab, other):
        firncore.bake(path, SNOW, suns=[sun], sky=firncore.Sky(), quality="DRAFT", seed=3)
    rays = down([(0.01 * i, -0.02 * i) for i in range(5)])
    assert np.array_equal(firncore.render_baked(slab, SNOW, *rays), firncore.render_baked(other, SNOW, *rays))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"quality": "ULTRA"}, "quality"),
        ({"sky_samples": -1}, "sample"),
        ({"occluders": [(np.zeros((3, 2), np.float32), np.zeros((1, 3), np.uint32), (0, 0, 0))]}, "vertices"),
        ({"occluders": [(np.zeros((3, 3), np.float32), np.array([[0, 1, 5]], np.uint32), (0, 0, 0))]}, "vertex"),
        ({"occluders": [(np.eye(3, dtype=np.float32), np.array([[0, 1, 2]], np.uint32), (2, 0, 0))]}, "albedo"),
    ],
)
def test_bad_input_is_a_value_error(slab, kwargs, message):
    with pytest.raises(ValueError, match=message):
        firncore.bake(slab, SNOW, **kwargs)


def test_bad_optics_and_lights_are_value_errors():
    with pytest.raises(ValueError, match="albedo"):
        firncore.VolumeOptics(10.0, (1.2, 1.0, 1.0), 0.85)
    with pytest.raises(ValueError, match="g"):
        firncore.VolumeOptics(10.0, (0.9, 0.9, 0.9), 1.0)
    with pytest.raises(ValueError, match="extinction"):
        firncore.VolumeOptics(-1.0, (0.9, 0.9, 0.9), 0.5)
    with pytest.raises(ValueError, match="direction"):
        firncore.SunLight((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="irradiance"):
        firncore.SunLight((0.0, 0.0, 1.0), (math.nan, 1.0, 1.0))
    with pytest.raises(ValueError, match="sky map"):
        firncore.Sky((1.0, 1.0, 1.0), np.zeros((4, 4), np.float32))


def test_file_problems(tmp_path):
    with pytest.raises(OSError):
        firncore.bake(os.fspath(tmp_path / "missing.vdb"), SNOW)
    import pyopenvdb

    grid = pyopenvdb.FloatGrid()
    grid.name = "not_density"
    grid.fill((0, 0, 0), (3, 3, 3), 300.0)
    path = os.fspath(tmp_path / "other.vdb")
    pyopenvdb.write(path, grids=[grid])
    with pytest.raises(ValueError, match="density"):
        firncore.bake(path, SNOW)


def test_rays_from_non_finite_origins_are_value_errors(slab):
    """Fuzzing (issue 11): a NaN origin went into the ray marcher (undefined float-to-int conversions)."""
    firncore.bake(slab, SNOW, quality="DRAFT")
    directions = np.array([[0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match="origins"):
        firncore.render_baked(slab, SNOW, np.array([[math.nan, 0.0, 1.0]]), directions)
    with pytest.raises(ValueError, match="origins"):
        firncore.monte_carlo_radiance(slab, SNOW, np.array([[0.0, math.inf, 1.0]]), directions, samples=1)


def test_huge_test_slab_is_a_budget_error(tmp_vdb):
    """Fuzzing: write_slab_vdb(width=100000) filled 1e10 voxels until memory ran out."""
    with pytest.raises(firncore.BudgetError, match="budget"):
        firncore.write_slab_vdb(tmp_vdb, voxel_size=0.01, width=100000, layers=100000, density=300.0)


def test_huge_sample_counts_are_value_errors(slab):
    """Fuzzing: huge counts ran for hours (no progress to cancel slab_monte_carlo); they are refused at once."""
    with pytest.raises(ValueError, match="sun samples"):
        firncore.bake(slab, SNOW, quality="DRAFT", sun_samples=10**9)
    with pytest.raises(ValueError, match="photons"):
        firncore.slab_monte_carlo(omega=0.9, g=0.0, tau=1.0, mu0=1.0, photons=10**12)
    with pytest.raises(ValueError, match="samples"):
        firncore.monte_carlo_radiance(slab, SNOW, np.zeros((1, 3)), np.array([[0.0, 0.0, -1.0]]), samples=10**9)


def test_occluders_of_the_wrong_kind_are_value_errors(slab):
    """Fuzzing: an occluder that is not a tuple, or a colour name as albedo, leaked pybind11's RuntimeError."""
    triangle = (np.eye(3, dtype=np.float32), np.array([[0, 1, 2]], np.uint32))
    with pytest.raises(ValueError, match="occluder"):
        firncore.bake(slab, SNOW, occluders=["wall"])
    with pytest.raises(ValueError, match="albedo"):
        firncore.bake(slab, SNOW, occluders=[(*triangle, "red")])
    with pytest.raises(ValueError, match="albedo"):
        firncore.bake(slab, SNOW, occluders=[(*triangle, (0.5, None, 0.5))])


def test_objects_baked_as_one_medium_each_get_the_unions_light_on_their_own_voxels(tmp_path):
    """bake_joint (transport/joint_medium.h): a narrow slab inside a wide one. Each output keeps its own density and
    holds the source grids of the union baked alone (union_density, then bake: same settings, same seed) where it
    has snow; the narrow one's grids stop a few voxels past its snow. Oracle: the union's own bake."""
    wide, narrow, union = (os.fspath(tmp_path / name) for name in ("wide.vdb", "narrow.vdb", "union.vdb"))
    firncore.write_slab_vdb(wide, voxel_size=0.01, width=32, layers=8, density=150.0)
    firncore.write_slab_vdb(narrow, voxel_size=0.01, width=8, layers=8, density=150.0)
    lit = [os.fspath(tmp_path / "wide_lit.vdb"), os.fspath(tmp_path / "narrow_lit.vdb")]
    light = dict(sky=firncore.Sky((1.0, 1.0, 1.0)), quality="DRAFT", seed=3)
    firncore.bake_joint([wide, narrow], lit, SNOW, **light)
    firncore.union_density([wide, narrow], union)
    firncore.bake(union, SNOW, **light)
    inside, outside = [0.0, 0.0, -0.03], [0.12, 0.0, -0.03]  # in both slabs; in the wide one only
    points = np.array([inside, outside], np.float32)
    assert firncore.sample_grid(union, "density", points) == pytest.approx([300.0, 150.0])
    assert firncore.sample_grid(lit[0], "density", points) == pytest.approx([150.0, 150.0])
    assert firncore.sample_grid(lit[1], "density", points) == pytest.approx([150.0, 0.0])
    for name in firncore.BAKED_GRID_NAMES:
        shared = firncore.sample_color_grid(union, name, points)
        np.testing.assert_allclose(firncore.sample_color_grid(lit[0], name, points), shared, rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(firncore.sample_color_grid(lit[1], name, points[:1]), shared[:1], rtol=1e-6,
                                   atol=1e-9)
        assert not firncore.sample_color_grid(lit[1], name, points[1:]).any()
    assert firncore.sample_color_grid(union, "firn_source", points).min() > 0.0  # lit where both are compared
    # Where the wide slab is alone, it renders as the union does.
    origins, directions = down([(0.12, 0.0)])
    np.testing.assert_allclose(firncore.render_baked(lit[0], SNOW, origins, directions),
                               firncore.render_baked(union, SNOW, origins, directions), rtol=1e-6)


def test_a_joint_bake_needs_an_output_per_file(slab):
    with pytest.raises(ValueError, match="one output path"):
        firncore.bake_joint([slab, slab], [None], SNOW)
