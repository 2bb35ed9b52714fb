"""Cache and file failures (docs/reliability.md): a cache folder that cannot be created, a read-only one, a full
disk, a .blend moved without its cache folder, a snow file deleted or truncated by hand. Each gives a clear
operator report, leaves no temporary file and keeps the previous file and object as they were.

Tests run as root, whom chmod does not stop: a read-only folder is a tmpfs remounted read-only, a full disk a
small tmpfs filled up (both skipped where mounting is not allowed); a folder that cannot be created is one whose
parent is a regular file."""

import errno
import glob
import os
import shutil
import subprocess

import bpy
import pytest

from bake_helpers import S, add_contract_grids, needs_core_bake, optics_with, uniform_source
from firn.bake import operators as bake, state as bake_state, ui as bake_ui
from firn.common import cache, preferences
from firn.material import nodes as materials
from firn.snow_layer import ui as snow_ui
from test_snow_material import RecordingLayout

WRITE_ADVICE = "Free some disk space, make the folder writable, or set a Cache Folder"


@pytest.fixture
def cache_folder(clean_scene):
    """Sets the add-on's Cache Folder preference; puts it back after the test."""
    prefs = preferences.get()
    yield lambda path: setattr(prefs, "cache_folder", str(path))
    prefs.cache_folder = ""


@pytest.fixture
def tmpfs(tmp_path):
    """mount(size) -> a folder on a tmpfs of `size` bytes; remount_read_only(folder). Unmounted after the test."""
    mounted = []

    def mount(size):
        folder = tmp_path / f"tmpfs{len(mounted)}"
        folder.mkdir()
        if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                          capture_output=True).returncode != 0:
            pytest.skip("cannot mount a tmpfs here (needs root)")
        mounted.append(folder)
        return folder

    def remount_read_only(folder):
        subprocess.run(["mount", "-o", "remount,ro", str(folder)], check=True)

    yield mount, remount_read_only
    for folder in mounted:
        subprocess.run(["umount", "-l", str(folder)], check=False)


def fill(folder):
    """Writes a file into `folder` until its disk is full."""
    try:
        with open(os.path.join(folder, "filler"), "wb") as file:
            while True:
                file.write(b"\0" * 4096)
                file.flush()
    except OSError as error:
        assert error.errno == errno.ENOSPC


def leftovers(folder):
    return glob.glob(os.path.join(folder, "**", "*.tmp*"), recursive=True) + \
        glob.glob(os.path.join(folder, "**", "*.firn-bake.vdb"), recursive=True)


def snow_on_plane():
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    assert bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.05, voxel_size=0.02) == {"FINISHED"}
    return bpy.context.object


def fake_bake(snow):
    """The baked grids in the snow's file and the add-on's post-bake step, as if Bake Scattering had run."""
    add_contract_grids(bake_state.snow_path(snow), uniform_source(S))
    bake.firncore.verify_file(bake_state.snow_path(snow))  # a full read: pyopenvdb says nothing when its write fails
    bake.adopt_bake(snow, optics_with(12.0), dict(bake.bake_inputs.signature(bpy.context, snow),
                                     optics=bake_state.optics_digest(snow)), "test grids")
    assert bake_state.changes(snow) == ("BAKED", [])


def read_bytes(path):
    with open(path, "rb") as file:
        return file.read()


def panel_labels(snow):
    log = {"props": [], "labels": [], "operators": [], "menus": []}
    snow_ui.draw_snow_layer(RecordingLayout(log), snow)
    bake_ui.draw_bake(RecordingLayout(log), snow)
    return log["labels"]


def test_a_cache_folder_that_cannot_be_created_is_reported_before_any_work(cache_folder, tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the cache folder should be")
    cache_folder(blocker / "cache")
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    with pytest.raises(RuntimeError, match=f"Cannot write snow files to .*Not a directory.*{WRITE_ADVICE}"):
        bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.05)
    assert "Snow" not in bpy.data.objects and not leftovers(str(tmp_path))


def baked_snow_in(folder, cache_folder):
    cache_folder(folder)
    snow = snow_on_plane()
    fake_bake(snow)
    return snow


def every_writer_fails_and_changes_nothing(snow, folder, reason):
    """Regenerate, Bake Scattering, Clear Bake and Add Snow Layer each report `reason` (a regex) and what to do,
    and leave the snow's file, its bake and the scene as they were, with no temporary file."""
    path = bake_state.snow_path(snow)
    before = read_bytes(path)
    with pytest.raises(RuntimeError, match=f"{reason}.*{WRITE_ADVICE}"):
        bpy.ops.firn.regenerate_snow()
    with pytest.raises(RuntimeError, match=f"{reason}.*{WRITE_ADVICE}"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")
    snow.select_set(True)
    with pytest.raises(RuntimeError, match=f"Cannot clear the bake of 'Snow' .*{reason}.*stays baked"):
        bpy.ops.firn.clear_bake()
    bpy.ops.object.select_all(action="DESELECT")
    bpy.data.objects["Plane"].select_set(True)
    with pytest.raises(RuntimeError, match=f"{reason}.*{WRITE_ADVICE}"):
        bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.05)

    assert read_bytes(path) == before and not leftovers(str(folder))
    assert bake_state.changes(snow) == ("BAKED", []) and materials.is_baked_material(materials.snow_material(snow))
    assert [obj.name for obj in bpy.data.objects if obj.type == "VOLUME"] == ["Snow"]


def test_a_read_only_cache_folder_keeps_the_snow_and_its_bake(cache_folder, tmpfs):
    """Found before any work starts."""
    mount, remount_read_only = tmpfs
    folder = mount(8 << 20)
    snow = baked_snow_in(folder, cache_folder)
    remount_read_only(folder)
    every_writer_fails_and_changes_nothing(snow, folder, "Read-only file system")
    with pytest.raises(RuntimeError, match=f"Cannot write snow files to {folder} \\(Read-only file system\\)"):
        bpy.ops.firn.regenerate_snow()


def test_a_full_disk_keeps_the_previous_file(cache_folder, tmpfs):
    """Found by the core while it writes (OpenVDB alone would rename the truncated file into place)."""
    folder = tmpfs[0](8 << 20)
    snow = baked_snow_in(folder, cache_folder)
    fill(folder)
    every_writer_fails_and_changes_nothing(snow, folder, "No space left on device")
    with pytest.raises(RuntimeError, match="cannot write .*Snow.vdb: No space left on device"):
        bpy.ops.firn.regenerate_snow()
    with pytest.raises(RuntimeError, match="cannot write .*Snow.vdb.firn-bake.vdb: No space left on device"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")
    os.remove(os.path.join(folder, "filler"))
    bpy.context.view_layer.objects.active = snow
    assert bpy.ops.firn.regenerate_snow() == {"FINISHED"}  # room again: it works


def saved_with_snow(directory):
    """A saved .blend with baked snow (its file in firn_cache/ beside it); returns the .blend's path."""
    snow = snow_on_plane()
    fake_bake(snow)
    blend = os.path.join(directory, "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)  # moves the snow's file beside the .blend, after writing it
    bpy.ops.wm.save_mainfile()  # the .blend names the moved file
    assert os.path.isfile(bake_state.snow_path(snow))
    return blend


def test_a_blend_moved_without_its_cache_folder_says_so_and_regenerates(clean_scene, tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    blend = saved_with_snow(str(tmp_path / "a"))
    moved = shutil.copy(blend, tmp_path / "b" / "scene.blend")
    bpy.ops.wm.open_mainfile(filepath=str(moved))
    snow = bpy.data.objects["Snow"]
    bpy.context.view_layer.objects.active = snow
    bpy.context.view_layer.update()

    problem = f"Snow file missing: {tmp_path / 'b' / 'firn_cache' / 'scene' / 'Snow.vdb'}"
    assert cache.file_problem(snow.data) == problem and problem in panel_labels(snow)
    assert bake_state.changes(snow) == ("OUTDATED", ["snow"])
    with pytest.raises(RuntimeError, match="Snow file missing: .*Regenerate the snow"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")

    assert bpy.ops.firn.regenerate_snow() == {"FINISHED"}  # from its targets, into the new cache folder
    assert cache.file_problem(snow.data) is None and os.path.isfile(bake_state.snow_path(snow))
    assert sorted(bake.firncore.grid_names(bake_state.snow_path(snow))) == ["density", "surface"]


def test_a_truncated_file_is_set_aside_on_load_and_regenerated(clean_scene, tmp_path):
    blend = saved_with_snow(str(tmp_path))
    path = str(tmp_path / "firn_cache" / "scene" / "Snow.vdb")
    with open(path, "r+b") as file:
        file.truncate(os.path.getsize(path) * 6 // 10)
    bpy.ops.wm.open_mainfile(filepath=blend)  # Blender 3.4 aborts if it reads this file itself
    snow = bpy.data.objects["Snow"]
    bpy.context.view_layer.objects.active = snow
    bpy.context.view_layer.update()

    assert snow.data.filepath == "" and cache.file_problem(snow.data) == f"Snow file damaged: {path}"
    assert f"Snow file damaged: {path}" in panel_labels(snow)
    with pytest.raises(RuntimeError, match="Snow file damaged: .*Regenerate the snow"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")

    assert bpy.ops.firn.regenerate_snow() == {"FINISHED"}
    assert cache.file_problem(snow.data) is None and bake_state.snow_path(snow) == path
    assert sorted(bake.firncore.grid_names(path)) == ["density", "surface"]


def test_a_file_deleted_or_truncated_during_the_session(clean_scene, tmp_path):
    snow = snow_on_plane()
    path = bake_state.snow_path(snow)
    with open(path, "r+b") as file:
        file.truncate(os.path.getsize(path) // 2)
    with pytest.raises(RuntimeError, match="Cannot read the volume of 'Snow' .*Regenerate the snow"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")
    os.remove(path)
    assert f"Snow file missing: {path}" in panel_labels(snow)
    with pytest.raises(RuntimeError, match="Snow file missing"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")
    assert bpy.ops.firn.rebuild_from_metaballs() == {"FINISHED"}
    assert cache.file_problem(snow.data) is None and not leftovers(os.path.dirname(path))


@needs_core_bake
def test_a_file_damaged_inside_its_voxels_is_found_by_the_bake(clean_scene, tmp_path):
    """The panels and the load-time check read a file's header only; the bake's own (single) read of the file
    finds damage inside its voxels, and says so apart from a failed write."""
    snow = snow_on_plane()
    path = bake_state.snow_path(snow)
    damaged = bytearray(read_bytes(path))
    damaged[len(damaged) // 2:len(damaged) // 2 + 64] = b"\xff" * 64  # same size: the header stays right
    with open(path, "wb") as file:
        file.write(damaged)
    assert cache.unreadable(path) is None  # cheap, at load: header and grid descriptors
    with pytest.raises(OSError):
        bake.firncore.verify_file(path)
    with pytest.raises(RuntimeError, match="Cannot read the volume of 'Snow' \\(cannot read .*Regenerate the snow"):
        bpy.ops.firn.bake_scattering(quality="DRAFT")
    assert read_bytes(path) == bytes(damaged) and not leftovers(os.path.dirname(path))
    assert not snow.firn.bake_fingerprint


def core_bake(snow):
    snow.select_set(True)
    bpy.context.view_layer.objects.active = snow
    assert bpy.ops.firn.bake_scattering(quality="DRAFT") == {"FINISHED"}
    assert bake_state.changes(snow) == ("BAKED", [])


@pytest.mark.parametrize("baked_by", [fake_bake, pytest.param(core_bake, marks=needs_core_bake)],
                         ids=["grids_written_here", "core_bake"])
def test_clear_bake_leaves_the_grids_the_file_had_before_the_bake(clean_scene, baked_by):
    import pyopenvdb

    def grids(path):
        found = pyopenvdb.readAll(path)[0]
        return {grid.name: (grid.transform.indexToWorld((1, 2, 3)),
                            sorted((item["min"], item["max"], item["value"]) for item in grid.citerOnValues()))
                for grid in found}

    snow = snow_on_plane()
    path = bake_state.snow_path(snow)
    before = grids(path)
    baked_by(snow)
    assert set(materials.BAKED_GRIDS) <= set(grids(path))
    snow.select_set(True)
    assert bpy.ops.firn.clear_bake() == {"FINISHED"}
    assert grids(path) == before  # density and surface: the same voxels, values and transforms
    assert not materials.has_baked_grids(snow.data) and not leftovers(os.path.dirname(path))
