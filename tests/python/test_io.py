"""Reading Firn's VDB files back through firncore (bind_io.cpp)."""

import math

import numpy as np
import pytest

import firncore


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
