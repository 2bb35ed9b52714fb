"""Firn's VDB files from Python (bind_io.cpp): reading grids back, and taking grids out again (Clear Bake)."""

import math
import os

import numpy as np
import pytest

import firncore

from test_snow import plane


@pytest.fixture
def slab(tmp_vdb):
    firncore.write_slab_vdb(tmp_vdb, voxel_size=0.01, width=4, layers=4, density=300.0)
    return tmp_vdb


def test_samples_inside_and_outside(slab):
    inside, outside = firncore.sample_grid(slab, "density", np.array([[0, 0, -0.02], [0, 0, 0.5]], np.float32))
    assert inside == pytest.approx(300.0) and outside == 0.0


def test_non_finite_points_are_value_errors(slab):
    """Fuzzing (issue 11): NaN went into OpenVDB's float-to-int voxel lookup (undefined behaviour)."""
    with pytest.raises(ValueError, match="point 1"):
        firncore.sample_grid(slab, "density", np.array([[0, 0, 0], [math.nan, 0, 0]], np.float32))


def test_points_beyond_the_index_range_hold_nothing(slab):
    """Fuzzing: 1e30 m is past OpenVDB's 32-bit coordinates; it samples the background, not a wrapped voxel."""
    far = firncore.sample_grid(slab, "density", np.array([[1e30, 0, 0], [0, -1e30, 0]], np.float32))
    assert list(far) == [0.0, 0.0]


def snow_file(path):
    firncore.generate_snow_layer(*plane(1.0), settings=firncore.SnowLayerSettings(depth=0.1, seed=1), path=path)
    return path


def test_remove_grids_leaves_the_others_as_they_were(tmp_path):
    path = snow_file(os.fspath(tmp_path / "snow.vdb"))
    points = np.random.default_rng(0).uniform([-0.5, -0.5, -0.05], [0.5, 0.5, 0.15], (400, 3)).astype(np.float32)
    before = {name: firncore.sample_grid(path, name, points) for name in ("density", "surface")}
    assert firncore.remove_grids(path, ["surface", "firn_source"]) == ["surface"]
    assert firncore.grid_names(path) == ["density"]
    assert np.array_equal(firncore.sample_grid(path, "density", points), before["density"])
    assert sorted(os.listdir(tmp_path)) == ["snow.vdb"]  # no temporary file left


def test_remove_grids_of_nothing_leaves_the_file_untouched(tmp_path):
    path = snow_file(os.fspath(tmp_path / "snow.vdb"))
    stamp = os.stat(path).st_mtime_ns
    assert firncore.remove_grids(path, ["firn_source"]) == []
    assert os.stat(path).st_mtime_ns == stamp


def test_remove_grids_refuses_to_empty_a_file_and_reports_missing_files(tmp_path):
    path = snow_file(os.fspath(tmp_path / "snow.vdb"))
    with pytest.raises(ValueError, match="empty"):
        firncore.remove_grids(path, ["density", "surface"])
    assert sorted(firncore.grid_names(path)) == ["density", "surface"]
    with pytest.raises(OSError):
        firncore.remove_grids(os.fspath(tmp_path / "none.vdb"), ["density"])


def test_read_and_write_failures_are_oserrors_of_their_own_kind(tmp_path):
    """A call that reads one file and writes another (the bake) says which one failed (issue 11)."""
    assert issubclass(firncore.ReadError, OSError) and issubclass(firncore.WriteError, OSError)
    with pytest.raises(firncore.ReadError, match="cannot read"):
        firncore.verify_file(os.fspath(tmp_path / "none.vdb"))
    path = snow_file(os.fspath(tmp_path / "snow.vdb"))
    with open(path, "r+b") as file:
        file.truncate(os.path.getsize(path) - 1)
    with pytest.raises(firncore.ReadError, match="truncated or corrupted"):
        firncore.grid_names(path)  # the header check sees a grid that ends past the file's end


def test_bake_reads_one_file_and_writes_another(tmp_path):
    """The add-on's bake reads the snow file once and writes a staged copy: the core does both, and says which
    failed."""
    source, output = os.fspath(tmp_path / "snow.vdb"), os.fspath(tmp_path / "baked.vdb")
    firncore.write_slab_vdb(source, voxel_size=0.02, width=4, layers=4, density=300.0)
    before = open(source, "rb").read()
    optics = firncore.VolumeOptics(10.0, (0.99, 0.99, 0.99), 0.8)
    firncore.bake(source, optics, sky=firncore.Sky(), quality="DRAFT", output_path=output)
    assert open(source, "rb").read() == before
    assert sorted(firncore.grid_names(output)) == sorted(["density"] + list(firncore.BAKED_GRID_NAMES))
    with pytest.raises(firncore.WriteError, match="cannot write"):
        firncore.bake(source, optics, sky=firncore.Sky(), quality="DRAFT",
                      output_path=os.fspath(tmp_path / "snow.vdb" / "inside_a_file.vdb"))
    damaged = bytearray(before)
    damaged[len(damaged) // 2:len(damaged) // 2 + 64] = b"\xff" * 64  # inside the voxels; the header is intact
    with open(source, "wb") as file:
        file.write(damaged)
    firncore.grid_names(source)
    with pytest.raises(firncore.ReadError, match="cannot read"):
        firncore.bake(source, optics, sky=firncore.Sky(), quality="DRAFT", output_path=output)


def test_sample_color_grid_reads_rgb_grids_and_refuses_others(tmp_vdb):
    """The viewport proxy's baked colours: firn_source sampled where the bake left light."""
    firncore.write_slab_vdb(tmp_vdb, voxel_size=0.01, width=8, layers=8, density=300.0)
    snow = firncore.optics(grain_radius=100e-6, density=300.0, g=0.85)
    firncore.bake(tmp_vdb, snow, sky=firncore.Sky((1.0, 1.0, 1.0)), quality="DRAFT")
    points = np.array([[0, 0, -0.005], [0, 0, 5.0]], np.float32)
    inside, far = firncore.sample_color_grid(tmp_vdb, "firn_source", points)
    assert inside.shape == (3,) and np.all(inside > 0.0) and list(far) == [0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="not an RGB"):
        firncore.sample_color_grid(tmp_vdb, "density", points)
    with pytest.raises(ValueError, match="no grid named"):
        firncore.sample_color_grid(tmp_vdb, "nothing", points)
    with pytest.raises(ValueError, match="point 0"):
        firncore.sample_color_grid(tmp_vdb, "firn_source", np.array([[math.nan, 0, 0]], np.float32))
