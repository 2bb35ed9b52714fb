"""A spray sequence's files (docs/spray.md "The sequence and its files"), made playable by Blender. No bpy here:
the worker thread calls these after the core.

The core writes snow_####.vdb only at frames whose tracks changed the snow (at the others the latest earlier one
holds); Blender plays a Volume sequence only where every frame has its file. So each frame without one gets a hard
link to the snow in force then (the input snow at the first frame): the same bytes, no copy. Every writer of these
files replaces them (temporary file, then rename), so a link keeps the snow it was made from.
"""

import json
import os
import shutil

from ..common.core import firncore


LIT_NAMES = {"lit": "lit_{frame:04d}.vdb", "lit_spray": "lit_spray_{frame:04d}.vdb"}


def frame_path(directory, frame, kind):
    """The path of a frame's file: kind "spray", "snow" (the core's), "lit" (the tracked snow with its baked
    light) or "lit_spray" (the lumps with theirs, spray/light.py)."""
    if kind in LIT_NAMES:
        return os.path.join(directory, LIT_NAMES[kind].format(frame=frame))
    spray, snow, _state = firncore.spray_frame_paths(directory, frame)
    return spray if kind == "spray" else snow


def sequence_paths(first_path, first, count):
    """The files a Volume sequence plays (operators.play_sequence: scene frame f plays frame f's file), frames
    first…first + count - 1, of the kind whose frame `first` file is `first_path`; ValueError where no kind's is."""
    directory, name = os.path.split(first_path)
    for kind in ("spray", "snow", *LIT_NAMES):
        if os.path.basename(frame_path(directory, first, kind)) == name:
            return [frame_path(directory, frame, kind) for frame in range(first, first + count)]
    raise ValueError(f"{first_path} is not the frame {first} file of a spray")


def medium_paths(directory, frame, snow_layer_path, tracked):
    """(snow, lumps) files a frame's light is baked from: its tracked snow where the spray has tracks (`tracked`;
    the file may be simulated only later), else the snow layer's own file (Cut Tracks off), and its lumps."""
    snow = frame_path(directory, frame, "snow") if tracked else snow_layer_path
    return snow, frame_path(directory, frame, "spray")


def marker_path(directory, frame):
    """The marker of a lit frame (spray/light.py): what its lit files were baked from."""
    return os.path.splitext(frame_path(directory, frame, "lit"))[0] + ".json"


def read_marker(directory, frame):
    """A lit frame's marker ({component: digest}), or None when it is missing or damaged."""
    try:
        with open(marker_path(directory, frame), encoding="utf-8") as stream:
            return json.load(stream)
    except (OSError, ValueError):
        return None


def fill_tracked_snow(directory, snow_path, first_frame, last_frame, snow_frames):
    """Gives every frame first_frame…last_frame a snow_####.vdb: the core's where it wrote one (`snow_frames`),
    elsewhere a link to the one in force. Returns the number of links made."""
    written, in_force, links = set(snow_frames), snow_path, 0
    for frame in range(first_frame, last_frame + 1):
        path = frame_path(directory, frame, "snow")
        if frame in written:
            in_force = path
            continue
        _link(in_force, path)
        links += 1
    return links


def _link(source, path):
    """`path` becomes `source`'s bytes, atomically: a hard link (a copy where links are not possible)."""
    staged = path + ".link"
    if os.path.lexists(staged):
        os.remove(staged)
    try:
        os.link(source, staged)
    except OSError:  # another file system, or one without hard links
        shutil.copyfile(source, staged)
    os.replace(staged, path)


def remove_sequence(directory):
    """Deletes a spray sequence's folder and everything in it; a folder already gone is fine (OSError else)."""
    try:
        shutil.rmtree(directory)
    except FileNotFoundError:
        pass
