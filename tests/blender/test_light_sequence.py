"""Bake Light Sequence and Clear Light Sequence in blender -b: a snow layer under a sun that sets over three frames
is baked frame by frame; each frame's light is the one Bake Scattering gives at that frame; frames baked from
the same scene are kept (resume, one frame per process); the panel's state follows the frame shown; Clear shows
the layer again; bad input is reported."""

import os

import bpy
import numpy as np
import pytest

from bake_helpers import uniform_world
from firn.bake import state as bake_state
from firn.common import cache
from firn.common.core import firncore
from firn.material import optics
from scene_helpers import save_in, saved_elsewhere_during, select_only

FRAMES = (2, 4)  # not from 1: the files' numbers are the scene's frames
ELEVATIONS = (1.4, 0.35)  # rad: the sun's elevation at the first and the last frame (80° and 20°)


def _lit_layer():
    """A 60 cm × 40 cm snow layer, 5 cm deep on 2 cm voxels, under a faint uniform sky and a sun that sinks from
    80° to 20° elevation over FRAMES."""
    bpy.ops.mesh.primitive_plane_add(size=1.0)
    plane = bpy.context.object
    plane.scale = (0.6, 0.4, 1.0)
    select_only(plane)
    assert bpy.ops.firn.add_snow_layer(depth=0.05, spacing=0.04, voxel_size=0.02, seed=1) == {"FINISHED"}
    snow = bpy.context.object
    uniform_world((0.05, 0.05, 0.05))
    bpy.ops.object.light_add(type="SUN", location=(0.0, 0.0, 2.0))
    sun = bpy.context.object
    sun.data.energy, sun.data.angle = 3.0, 0.01
    for frame, elevation in zip(FRAMES, ELEVATIONS):
        sun.rotation_euler = (np.pi / 2 - elevation, 0.0, 0.0)  # the sun's light falls along its local -z
        sun.keyframe_insert("rotation_euler", frame=frame)
    select_only(snow)
    return snow, sun


def shutil_usage(free):
    """shutil.disk_usage's answer for a disk with `free` bytes left."""
    import collections

    return collections.namedtuple("usage", "total used free")(free, 0, free)


def _lit_files(lit):
    folder = os.path.normpath(os.path.dirname(bpy.path.abspath(lit.data.filepath)))  # '//../first/…' once moved
    return [os.path.join(folder, f"lit_{frame:04d}.vdb") for frame in range(FRAMES[0], FRAMES[1] + 1)]


def _drawn_above(path, obj):
    """What Cycles draws for baked snow seen straight down at five points of the layer, W/m²/sr (green mean)."""
    x = np.linspace(-0.2, 0.2, 5)
    origins = np.stack([x, np.zeros(5), np.ones(5)], 1)
    directions = np.tile([0.0, 0.0, -1.0], (5, 1))
    return firncore.render_baked(path, optics.volume_optics(obj.firn), origins, directions)[:, 1].mean()


def _bake_frames(**settings):
    assert bpy.ops.firn.bake_light_sequence(**dict(dict(frame_start=FRAMES[0], frame_end=FRAMES[1],
                                                        quality="DRAFT"), **settings)) == {"FINISHED"}
    return next(obj for obj in bpy.data.objects if obj.firn.spray.role == "LIGHT")


def test_each_frame_is_lit_as_bake_scattering_lights_it_at_that_frame(clean_scene):
    snow, _sun = _lit_layer()
    snow_file = bpy.path.abspath(snow.data.filepath)
    lit = _bake_frames()
    files = _lit_files(lit)
    assert all(set(firncore.BAKED_GRID_NAMES) <= set(firncore.grid_names(path)) for path in files)
    assert lit.data.is_sequence and os.path.basename(lit.data.filepath) == os.path.basename(files[0])
    assert lit.active_material.get("firn_form", "").startswith("BAKED")
    assert snow.hide_render and snow.hide_viewport and not lit.hide_render  # the Lit Volume plays in its place
    assert lit.parent == snow and "Draft light" in lit.firn.bake_summary
    drawn = [_drawn_above(path, lit) for path in files]
    # A sun at 80° lights the snow more than one at 20° (the irradiance alone: sin 80° / sin 20° = 2.9).
    assert drawn[0] > 1.5 * drawn[-1] > 0.0
    # The oracle: Bake Scattering of the layer at each frame, same quality and seed (its file is the snow's own,
    # rewritten: the last check).
    for frame, path in zip(range(FRAMES[0], FRAMES[1] + 1), files):
        bpy.context.scene.frame_set(frame)
        select_only(snow)
        assert bpy.ops.firn.bake_scattering(quality="DRAFT", seed=0) == {"FINISHED"}
        assert _drawn_above(snow_file, snow) == pytest.approx(_drawn_above(path, lit), rel=1e-6)
    # The snow file changed (baked): every lit frame is from other snow now.
    assert bake_state.changes(lit) == (bake_state.OUTDATED, ["snow"])


def test_an_animated_world_lights_each_frame_as_it_stands_then(clean_scene):
    """A Nishita sky whose sun sets over the frames (no sun lamp): the core computes the sky at each frame, as Bake
    Scattering does at that frame."""
    snow, sun = _lit_layer()
    bpy.data.objects.remove(sun)
    world = bpy.data.worlds.new("Sunset")
    world.use_nodes = True
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type, sky.sun_disc = "NISHITA", False
    world.node_tree.links.new(sky.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    for frame, elevation in zip(FRAMES, ELEVATIONS):
        sky.sun_elevation = elevation
        sky.keyframe_insert("sun_elevation", frame=frame)
    bpy.context.scene.world = world
    lit = _bake_frames()
    files = _lit_files(lit)
    first, last = _drawn_above(files[0], lit), _drawn_above(files[-1], lit)
    assert first > 1.2 * last > 0.0  # a high sun's sky is brighter than a low one's
    for frame, path in ((FRAMES[0], files[0]), (FRAMES[1], files[-1])):
        bpy.context.scene.frame_set(frame)
        select_only(snow)
        assert bpy.ops.firn.bake_scattering(quality="DRAFT", seed=0) == {"FINISHED"}
        assert _drawn_above(bpy.path.abspath(snow.data.filepath), snow) == pytest.approx(_drawn_above(path, lit),
                                                                                          rel=1e-6)


def test_lit_frames_are_kept_resumed_and_baked_one_per_process_alike(clean_scene):
    snow, sun = _lit_layer()
    lit = _bake_frames()
    files = _lit_files(lit)
    drawn = [_drawn_above(path, lit) for path in files]
    stamps = [os.stat(path).st_mtime_ns for path in files]
    assert _bake_frames() == lit and "(0 baked now" in lit.firn.bake_summary
    assert [os.stat(path).st_mtime_ns for path in files] == stamps
    # The Lit Volume is left out of the depsgraph while the scene steps through the frames (spray/light.py), and
    # shown or hidden afterwards as the user had it.
    assert not lit.hide_viewport
    lit.hide_viewport = True
    assert _bake_frames() == lit and lit.hide_viewport
    lit.hide_viewport = False
    # Interrupted before the last frame: its file and marker were never written. The bake resumes there.
    os.remove(files[-1])
    os.remove(os.path.splitext(files[-1])[0] + ".json")
    assert _bake_frames() == lit and "(1 baked now" in lit.firn.bake_summary
    assert os.stat(files[0]).st_mtime_ns == stamps[0]
    assert _drawn_above(files[-1], lit) == pytest.approx(drawn[-1], rel=1e-6)
    # A render-farm node bakes the middle frame alone: the same light; the Lit Volume still plays every frame.
    os.remove(files[1])
    assert _bake_frames(frame_start=FRAMES[0] + 1, frame_end=FRAMES[0] + 1) == lit
    assert "(1 baked now" in lit.firn.bake_summary
    assert _drawn_above(files[1], lit) == pytest.approx(drawn[1], rel=1e-6)
    assert (lit.firn.spray.frame_start, lit.firn.spray.frame_end) == FRAMES
    assert lit.data.frame_duration == FRAMES[1] - FRAMES[0] + 1
    # The panel's state: the marker of the frame shown against the scene at that frame.
    bpy.context.scene.frame_set(FRAMES[0] + 1)
    assert bake_state.changes(lit) == (bake_state.BAKED, [])
    sun.data.energy = 5.0
    assert bake_state.changes(lit) == (bake_state.OUTDATED, ["lamps"])
    sun.data.energy = 3.0
    snow.location.x += 0.5  # the layer moved (its Lit Volume with it): its ground and shadows are elsewhere
    bpy.context.view_layer.update()
    assert bake_state.changes(lit) == (bake_state.OUTDATED, ["snow"])  # a sun: the same light, elsewhere
    snow.location.x -= 0.5
    bpy.context.view_layer.update()
    assert bake_state.changes(lit) == (bake_state.BAKED, [])
    lit.firn.extinction_per_density *= 2.0  # the Lit Volume's own optics (its Snow Material panel)
    lit.firn.optics_mode = "CUSTOM"
    assert bake_state.changes(lit) == (bake_state.OUTDATED, ["optics"])
    assert _bake_frames() == lit and "(3 baked now" in lit.firn.bake_summary
    assert bake_state.changes(lit) == (bake_state.BAKED, [])


def test_a_layer_lit_while_the_file_is_saved_elsewhere_plays_the_frames_its_job_wrote(clean_scene, tmp_path,
                                                                                     monkeypatch):
    """The user saves the file into another folder (Save As) while Bake Light Sequence runs: the Lit Volume plays
    the frames the job wrote, by a path relative to the .blend where it stands now (the path taken when the job
    started named files beside the moved .blend that do not exist: review finding)."""
    from firn.bake.sequence import FIRN_OT_bake_light_sequence

    snow, _sun = _lit_layer()
    save_in(tmp_path / "first")
    written = cache.spray_folder(f"{snow.name} Lit")[0]  # beside the first .blend
    saved_elsewhere_during(monkeypatch, FIRN_OT_bake_light_sequence, tmp_path / "second" / "scene.blend")
    lit = _bake_frames()
    assert lit.data.filepath.startswith("//")
    files = _lit_files(lit)
    assert os.path.dirname(files[0]) == written
    assert all(os.path.isfile(path) for path in files)


def test_clear_light_sequence_shows_the_snow_layer_again(clean_scene):
    snow, _sun = _lit_layer()
    lit = _bake_frames()
    folder = os.path.dirname(_lit_files(lit)[0])
    select_only(lit)
    assert bpy.ops.firn.clear_light_sequence() == {"FINISHED"}
    assert not any(obj.firn.spray.role != "NONE" for obj in bpy.data.objects)
    assert not os.path.exists(folder)
    assert not snow.hide_render and not snow.hide_viewport
    assert os.path.exists(bpy.path.abspath(snow.data.filepath))


def test_bad_input_is_reported(clean_scene, monkeypatch):
    snow, _sun = _lit_layer()
    with pytest.raises(RuntimeError, match="must not come before"):
        bpy.ops.firn.bake_light_sequence(frame_start=5, frame_end=3)
    # A disk without room for the frames' files: nothing is baked (no Lit Volume, no file).
    from firn.bake import sequence

    snow_bytes = os.path.getsize(bpy.path.abspath(snow.data.filepath))
    monkeypatch.setattr(sequence.shutil, "disk_usage", lambda path: shutil_usage(free=snow_bytes))
    with pytest.raises(RuntimeError, match="3 frames of light need about"):
        bpy.ops.firn.bake_light_sequence(frame_start=FRAMES[0], frame_end=FRAMES[1])
    assert not any(obj.firn.spray.role == "LIGHT" for obj in bpy.data.objects)
    monkeypatch.undo()
    lit = _bake_frames()
    select_only(lit)
    with pytest.raises(RuntimeError, match="Bake Light Sequence bakes its light again"):
        bpy.ops.firn.bake_scattering()
    assert not bpy.ops.firn.clear_snow_spray.poll()  # a Lit Volume is not a spray
    lit.firn.spray.source = None  # its snow layer deleted
    with pytest.raises(RuntimeError, match="its snow layer was deleted"):
        bpy.ops.firn.bake_light_sequence()
    select_only(snow)
    bpy.context.view_layer.objects.active = None
    assert not bpy.ops.firn.bake_light_sequence.poll()


def test_a_lit_layer_and_a_spray_s_tracks_never_play_together(clean_scene):
    """Both would render in the layer's place: the second is refused, whichever comes first."""
    snow, _sun = _lit_layer()
    tracks = bpy.data.objects.new("Tracks", bpy.data.volumes.new("Tracks"))
    bpy.context.collection.objects.link(tracks)
    tracks.firn.spray.role, tracks.firn.spray.source = "TRACKS", snow
    select_only(snow)
    with pytest.raises(RuntimeError, match="tracks playing in its place"):
        bpy.ops.firn.bake_light_sequence(frame_start=FRAMES[0], frame_end=FRAMES[1])
    bpy.data.objects.remove(tracks)
    _bake_frames()
    bpy.ops.mesh.primitive_plane_add(size=0.1)
    ski = bpy.context.object
    select_only(snow, ski)
    with pytest.raises(RuntimeError, match="is lit frame by frame"):
        bpy.ops.firn.add_snow_spray(frame_start=FRAMES[0], frame_end=FRAMES[1])


def test_the_bake_panel_offers_a_light_sequence_on_a_layer_and_its_lit_volume(clean_scene):
    from firn.bake import ui as bake_ui
    from test_snow_material import RecordingLayout

    def draw(obj):
        log = {"props": [], "labels": [], "operators": [], "menus": []}
        bake_ui.draw_bake(RecordingLayout(log), obj)
        return log

    snow, _sun = _lit_layer()
    assert {"firn.bake_scattering", "firn.clear_bake", "firn.bake_light_sequence"} <= set(draw(snow)["operators"])
    lit = _bake_frames()
    log = draw(lit)
    assert {"firn.bake_light_sequence", "firn.clear_light_sequence"} <= set(log["operators"])
    assert "firn.bake_scattering" not in log["operators"]
    assert f"Lit frame by frame: {snow.name}, frames {FRAMES[0]}-{FRAMES[1]}" in log["labels"]
    assert not bpy.types.FIRN_PT_snow_spray.poll(type("Context", (), {"object": lit}))  # not a spray
