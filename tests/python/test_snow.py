"""Add Snow Layer through firncore, under /usr/bin/python3 without Blender."""

import os
import subprocess
import sys

import numpy as np
import pytest

import firncore
from conftest import cancelled_while_running


def plane(size=2.0, z=0.0):
    h = size / 2
    vertices = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]], np.float32)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], np.uint32)


def test_writes_density_and_surface_grids(tmp_vdb):
    result = firncore.generate_snow_layer(*plane(), settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb)
    assert sorted(firncore.grid_names(tmp_vdb)) == ["density", "surface"]
    density = firncore.grid_statistics(tmp_vdb, "density")
    assert density["active_voxels"] == result["active_voxels"] > 0
    assert 0.0 <= density["min"] and density["max"] <= 350.0  # never above the bottom density (kg/m^3)
    assert 120.0 < result["mean_density"] < 350.0
    balls = result["metaballs"]
    n = len(balls["radii"])
    assert balls["centres"].shape == (n, 3) and balls["normals"].shape == (n, 3)
    assert n >= result["site_count"] > 0
    inside, outside = firncore.sample_grid(tmp_vdb, "density", np.array([[0, 0, 0.05], [0, 0, 0.2]], np.float32))
    assert inside > 100.0 and outside == 0.0


def test_kept_metaballs_rebuild_the_same_file(tmp_path):
    settings = firncore.SnowLayerSettings(depth=0.1, seed=4)
    first, second = os.fspath(tmp_path / "a.vdb"), os.fspath(tmp_path / "b.vdb")
    result = firncore.generate_snow_layer(*plane(1.0), settings=settings, path=first)
    again = firncore.rasterize_metaballs(result["metaballs"], settings, second)
    assert again["active_voxels"] == result["active_voxels"]
    points = np.random.default_rng(0).uniform([-0.5, -0.5, 0], [0.5, 0.5, 0.15], (500, 3)).astype(np.float32)
    assert np.array_equal(firncore.sample_grid(first, "density", points), firncore.sample_grid(second, "density", points))


def test_surface_mesh_is_closed_and_above_the_ground(tmp_vdb):
    firncore.generate_snow_layer(*plane(1.0), settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb)
    vertices, triangles = firncore.snow_surface_mesh(tmp_vdb)
    assert len(triangles) > 100
    assert vertices[:, 2].max() == pytest.approx(0.1, abs=0.02)
    # Closed: every edge is shared by exactly two triangles.
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)


def test_proxy_meshed_in_memory_is_the_files_mesh(tmp_path):
    # The mesh made while the file is written is the one snow_surface_mesh makes from the file, exactly.
    settings = firncore.SnowLayerSettings(depth=0.1, seed=2)
    meshing = {"adaptivity": 0.0, "max_triangles": 2000, "isovalue": 0.75 * settings.effective_voxel_size}
    first, second = os.fspath(tmp_path / "a.vdb"), os.fspath(tmp_path / "b.vdb")
    result = firncore.generate_snow_layer(*plane(1.0), settings=settings, path=first, proxy_mesh=meshing)
    rebuilt = firncore.rasterize_metaballs(result["metaballs"], settings, second, proxy_mesh=meshing)
    from_file = firncore.snow_surface_mesh(first, **meshing)
    assert 100 < len(from_file[1]) <= 2000
    for made in (result["proxy"], rebuilt["proxy"]):
        assert all(np.array_equal(a, b) for a, b in zip(made, from_file))
    assert "proxy" not in firncore.generate_snow_layer(*plane(1.0), settings=settings, path=first)
    with pytest.raises(ValueError, match="unknown setting 'budget'"):
        firncore.generate_snow_layer(*plane(1.0), settings=settings, path=first, proxy_mesh={"budget": 10})


def test_reports_progress(tmp_vdb):
    seen = []
    progress = firncore.Progress(lambda fraction, stage: seen.append((fraction, stage)))
    firncore.generate_snow_layer(*plane(3.0), settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb,
                                 progress=progress)
    assert seen[-1][0] == 1.0
    assert progress.fraction == 1.0


def test_releases_the_gil_and_cancels_writing_nothing(tmp_vdb):
    progress = firncore.Progress()
    assert cancelled_while_running(
        lambda: firncore.generate_snow_layer(*plane(8.0), settings=firncore.SnowLayerSettings(depth=0.1, spacing=0.02),
                                             path=tmp_vdb, progress=progress), progress)
    assert not os.path.exists(tmp_vdb)


@pytest.mark.parametrize(
    "vertices, triangles, message",
    [
        (np.zeros((3, 2), np.float32), np.array([[0, 1, 2]], np.uint32), "vertices must be an \\(N, 3\\)"),
        (np.array([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], np.float32), np.array([[0, 1, 2]], np.uint32), "non-finite"),
        (np.eye(3, dtype=np.float32), np.array([[0, 1, 5]], np.uint32), "refers to vertex 5"),
        (np.eye(3, dtype=np.float32), np.zeros((0, 3), np.uint32), "no target triangles"),
    ],
)
def test_bad_geometry_raises_value_error(tmp_vdb, vertices, triangles, message):
    with pytest.raises(ValueError, match=message):
        firncore.generate_snow_layer(vertices, triangles, settings=firncore.SnowLayerSettings(), path=tmp_vdb)
    assert not os.path.exists(tmp_vdb)


def test_bad_settings_name_the_setting():
    with pytest.raises(ValueError, match="depth"):
        firncore.SnowLayerSettings(depth=-0.1).validate()
    with pytest.raises(ValueError, match="direction"):
        firncore.SnowLayerSettings(direction=(0, 0, 1)).validate()
    with pytest.raises(TypeError, match="no 'deepth'"):
        firncore.SnowLayerSettings(deepth=0.1)


def test_over_budget_suggests_a_voxel_size(tmp_vdb):
    settings = firncore.SnowLayerSettings(depth=0.1, voxel_size=0.002, max_voxels=2e6)
    with pytest.raises(firncore.BudgetError, match=r"voxel size of at least [0-9.]+ m"):
        firncore.generate_snow_layer(*plane(10.0), settings=settings, path=tmp_vdb)


def test_occluders_shelter_the_targets(tmp_vdb):
    box_v = np.array([[x, y, z] for z in (1.0, 1.1) for y in (-0.5, 0.5) for x in (-0.5, 0.5)], np.float32)
    box_t = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
                      [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]], np.uint32)
    firncore.generate_snow_layer(*plane(4.0), occluders=(box_v, box_t), settings=firncore.SnowLayerSettings(),
                                 path=tmp_vdb)
    under, beside = firncore.sample_grid(tmp_vdb, "density", np.array([[0, 0, 0.03], [1.5, 0, 0.03]], np.float32))
    assert under == 0.0 and beside > 100.0


def test_pyopenvdb_still_imports_after_firncore_used_openvdb(tmp_path):
    # Regression: exported OpenVDB template statics in the module crashed openvdb::initialize() in pyopenvdb.
    script = (
        "import numpy as np, firncore\n"
        "v = np.array([[0,0,0],[1,0,0],[0,1,0]], np.float32); t = np.array([[0,1,2]], np.uint32)\n"
        f"firncore.generate_snow_layer(v, t, settings=firncore.SnowLayerSettings(), path={str(tmp_path / 'x.vdb')!r})\n"
        "import pyopenvdb\n"
        f"print(pyopenvdb.read({str(tmp_path / 'x.vdb')!r}, 'density').activeVoxelCount())\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=os.environ)
    assert done.returncode == 0, done.stderr
    assert int(done.stdout) > 0


def test_open_surface_facing_down_gets_snow_on_its_upper_side(tmp_vdb):
    """A plane wound clockwise seen from above (normals down) is open: its normals are ignored and counted."""
    vertices, triangles = plane()
    result = firncore.generate_snow_layer(vertices, triangles[:, ::-1].copy(),
                                          settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb)
    assert result["open_surfaces_turned"] == 1
    above, below = firncore.sample_grid(tmp_vdb, "density", np.array([[0, 0, 0.05], [0, 0, -0.05]], np.float32))
    assert above > 100.0 and below == 0.0
    upright = firncore.generate_snow_layer(*plane(), settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb)
    assert upright["open_surfaces_turned"] == 0


def test_indices_that_numpy_would_wrap_are_value_errors(tmp_vdb):
    """Fuzzing (issue 11): int64 index 2**32 + 3 was cast to uint32 3, a valid vertex: a silently wrong mesh."""
    vertices, _ = plane()
    settings = firncore.SnowLayerSettings(depth=0.1)
    for bad in (2**32 + 3, -1):
        triangles = np.array([[0, 1, 2], [0, 2, bad]], np.int64)
        with pytest.raises(ValueError, match="not a vertex index"):
            firncore.generate_snow_layer(vertices, triangles, settings=settings, path=tmp_vdb)
    with pytest.raises(ValueError, match="not a vertex index"):
        firncore.generate_snow_layer(vertices, np.array([[0, 1, 2.5]]), settings=settings, path=tmp_vdb)


def test_arguments_of_the_wrong_kind_are_value_errors(tmp_vdb):
    """Fuzzing: a string inside occluders or metaballs leaked pybind11's cast error as a RuntimeError."""
    settings = firncore.SnowLayerSettings(depth=0.1)
    with pytest.raises(ValueError, match="occluders must be"):
        firncore.generate_snow_layer(*plane(), occluders="table", settings=settings, path=tmp_vdb)
    with pytest.raises(ValueError, match="vertices must be an array of numbers"):
        firncore.generate_snow_layer(*plane(), occluders=(["a", "b", "c"], [[0, 1, 2]]), settings=settings,
                                     path=tmp_vdb)
    balls = firncore.generate_snow_layer(*plane(1.0), settings=settings, path=tmp_vdb)["metaballs"]
    with pytest.raises(ValueError, match="centres"):
        firncore.rasterize_metaballs({**balls, "centres": "here"}, settings, tmp_vdb)


def test_surface_mesh_meets_a_triangle_budget_near_the_surface(tmp_vdb):
    firncore.generate_snow_layer(*plane(1.0), settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb)
    _vertices, full = firncore.snow_surface_mesh(tmp_vdb)
    budget = len(full) // 10
    vertices, triangles = firncore.snow_surface_mesh(tmp_vdb, adaptivity=0.1, max_triangles=budget)
    assert budget // 20 < len(triangles) <= budget
    assert vertices.dtype == np.float32 and vertices.shape[1] == 3 and triangles.dtype == np.uint32
    assert triangles.max() < len(vertices)
    # Still the snow: its top at the depth (10 cm on level ground), every vertex near the level set's zero.
    assert vertices[:, 2].max() == pytest.approx(0.1, abs=0.02)
    distance = firncore.sample_grid(tmp_vdb, "surface", vertices)
    assert np.abs(distance).max() < 0.1  # within the coarsest voxel the budget can have needed


def test_surface_mesh_refuses_bad_settings(tmp_vdb):
    firncore.generate_snow_layer(*plane(1.0), settings=firncore.SnowLayerSettings(depth=0.1), path=tmp_vdb)
    with pytest.raises(ValueError, match="adaptivity"):
        firncore.snow_surface_mesh(tmp_vdb, adaptivity=2.0)
    with pytest.raises(ValueError, match="budget"):
        firncore.snow_surface_mesh(tmp_vdb, max_triangles=10)
    with pytest.raises(TypeError):
        firncore.snow_surface_mesh(tmp_vdb, max_triangles=-1)


def test_depth_weights_are_checked(tmp_vdb):
    settings = firncore.SnowLayerSettings(depth=0.1)
    with pytest.raises(ValueError, match="3 for 4 target vertices"):
        firncore.generate_snow_layer(*plane(1.0), settings=settings, path=tmp_vdb, weights=[1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="between 0 and 1"):
        firncore.generate_snow_layer(*plane(1.0), settings=settings, path=tmp_vdb, weights=[1.0, 1.0, 1.5, 1.0])
    with pytest.raises(ValueError, match="no snow lands"):  # weight 0 everywhere
        firncore.generate_snow_layer(*plane(1.0), settings=settings, path=tmp_vdb, weights=[0.0, 0.0, 0.0, 0.0])


def test_snow_canvas_paints_and_refuses_bad_strokes(tmp_vdb):
    settings = firncore.SnowLayerSettings(depth=0.1)
    layer = firncore.generate_snow_layer(*plane(2.0), settings=settings, path=tmp_vdb)
    canvas = firncore.SnowCanvas(layer["metaballs"], settings, tmp_vdb, *plane(2.0))
    assert canvas.active_voxels == layer["active_voxels"]
    stats = canvas.stroke([[0.3, 0.0, 0.1]], [1.0], "ADD", 0.2, 0.05)
    assert stats["added"] > 0 and stats["leaves"] < canvas.leaf_count
    assert len(canvas.metaballs()["radii"]) == len(layer["metaballs"]["radii"]) + stats["added"]
    with pytest.raises(ValueError, match="brush mode"):
        canvas.stroke([[0.3, 0.0, 0.1]], [1.0], "PAINT", 0.2, 0.05)
    with pytest.raises(ValueError, match="one pressure per"):
        canvas.stroke([[0.3, 0.0, 0.1]], [1.0, 1.0], "ADD", 0.2, 0.05)
    with pytest.raises(ValueError, match="pressure"):
        canvas.stroke([[0.3, 0.0, 0.1]], [2.0], "ADD", 0.2, 0.05)
    coarse = firncore.SnowLayerSettings(depth=0.1, voxel_size=0.02)
    with pytest.raises(ValueError, match="rebuild it from its metaballs"):
        firncore.SnowCanvas(layer["metaballs"], coarse, tmp_vdb, *plane(2.0))


def ground_camera(pixel_angle=4e-3, half_angle=0.3):
    return firncore.CameraFootprint(position=(0.0, -2.0, 1.0), forward=(0.0, 1.0, 0.0), pixel_angle=pixel_angle,
                                    view_half_angle=half_angle)


def test_snow_bands_one_file_per_band_with_doubling_voxels(tmp_path):
    vertices, triangles = plane(60.0)
    vertices[:, 1] += 28.0  # ahead of the camera
    settings = firncore.SnowLayerSettings(depth=0.2, spacing=0.1, voxel_size=0.02, exposure_rays=4)
    pattern = str(tmp_path / "snow_{level}.vdb")
    result = firncore.generate_snow_bands(vertices, triangles, settings=settings, camera=ground_camera(),
                                          path_pattern=pattern)
    bands = result["bands"]
    assert [band["level"] for band in bands] == list(range(len(bands))) and len(bands) >= 3
    for band in bands:
        assert band["voxel_size"] == pytest.approx(0.02 * 2 ** band["level"])
        assert band["spacing"] == pytest.approx(0.1 * 2 ** band["level"])
        assert firncore.grid_statistics(band["path"], "density")["active_voxels"] == band["active_voxels"] > 0
        # A pixel spans the band's voxel where the band starts (4 mrad per pixel).
        assert band["near_distance"] == pytest.approx(band["voxel_size"] / 4e-3 if band["level"] else 0.0)
    assert sorted(os.listdir(tmp_path)) == sorted(f"snow_{band['level']}.vdb" for band in bands)
    assert result["out_of_view"] > 0 and len(result["metaballs"]["radii"]) > 0


def test_snow_bands_need_a_level_in_the_path_and_a_sane_camera(tmp_path):
    settings = firncore.SnowLayerSettings(depth=0.2, spacing=0.1, voxel_size=0.02)
    with pytest.raises(ValueError, match="needs '\\{level\\}'"):
        firncore.generate_snow_bands(*plane(), settings=settings, camera=ground_camera(),
                                     path_pattern=str(tmp_path / "snow.vdb"))
    with pytest.raises(ValueError, match="pixel angle"):
        firncore.generate_snow_bands(*plane(), settings=settings, camera=ground_camera(pixel_angle=0.0),
                                     path_pattern=str(tmp_path / "snow_{level}.vdb"))
    behind = firncore.CameraFootprint(position=(0.0, 10.0, 1.0), forward=(0.0, 1.0, 0.0), pixel_angle=1e-3,
                                      view_half_angle=0.3)
    with pytest.raises(ValueError, match="camera's view"):
        firncore.generate_snow_bands(*plane(), settings=settings, camera=behind,
                                     path_pattern=str(tmp_path / "snow_{level}.vdb"))
    assert os.listdir(tmp_path) == []


def test_lod_voxel_size_follows_the_pixel_footprint():
    camera = ground_camera(pixel_angle=1e-3)
    assert firncore.lod_voxel_size(1.0, camera, 0.01) == 0.01
    assert firncore.lod_voxel_size(25.0, camera, 0.01) == 0.02   # 2.5 cm per pixel
    assert firncore.lod_voxel_size(700.0, camera, 0.01) == 0.64  # 70 cm per pixel


def bumpy_ground(cells=16, size=1.0):
    """A (cells × cells)-quad ground whose heights vary (slopes every way: each triangle its own draws)."""
    x, y = np.meshgrid(np.linspace(-size / 2, size / 2, cells + 1), np.linspace(-size / 2, size / 2, cells + 1))
    z = 0.05 * np.sin(7.0 * x) * np.cos(5.0 * y)
    vertices = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype(np.float32)
    corner = (np.arange(cells)[:, None] * (cells + 1) + np.arange(cells)[None, :]).reshape(-1)
    quads = np.stack([corner, corner + 1, corner + cells + 2, corner + cells + 1], axis=1)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.uint32)
    return vertices, triangles


def test_the_triangles_order_does_not_change_the_snow(tmp_path):
    # Blender hands a script-made mesh's triangles in an order that changes from one process to the next (a UV
    # sphere's faces; the triangles and their corners the same): the snow must not depend on it.
    vertices, triangles = bumpy_ground()
    order = np.random.default_rng(3).permutation(len(triangles))
    settings = firncore.SnowLayerSettings(depth=0.08, spacing=0.02, seed=5)
    paths = [os.fspath(tmp_path / f"{name}.vdb") for name in ("given", "permuted")]
    given = firncore.generate_snow_layer(vertices, triangles, settings=settings, path=paths[0])
    permuted = firncore.generate_snow_layer(vertices, triangles[order].copy(), settings=settings, path=paths[1])
    assert permuted["site_count"] == given["site_count"] > 1000
    assert permuted["active_voxels"] == given["active_voxels"]
    key = lambda balls: np.lexsort(balls["centres"].T)
    for name in ("centres", "radii"):
        assert np.array_equal(given["metaballs"][name][key(given["metaballs"])],
                              permuted["metaballs"][name][key(permuted["metaballs"])])
    points = np.random.default_rng(0).uniform([-0.5, -0.5, -0.05], [0.5, 0.5, 0.15], (4000, 3)).astype(np.float32)
    # The same voxels; their values summed over the balls in another order: equal to float rounding (measured:
    # 6e-5 kg/m³ of 250, a few ulp).
    for grid, rounding in (("density", 1e-3), ("surface", 1e-6)):  # kg/m³, m
        np.testing.assert_allclose(firncore.sample_grid(paths[1], grid, points),
                                   firncore.sample_grid(paths[0], grid, points), rtol=0.0, atol=rounding)
