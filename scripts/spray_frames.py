"""Headless frame-range bake of the Snow Sprays of a .blend, for scripts and render farms (docs/user-guide.md,
"Snow Spray on a render farm"): opens the file with Firn enabled, runs Bake Sequence (the simulation up to --end,
resumed at the first frame missing on disk; the light of the lumps and the tracked snow at frames --start…--end),
then renders the frames asked for with the file's render settings.

blender -b --factory-startup --python scripts/spray_frames.py -- FILE.blend --end 120 [--start 1] [--render 1 120]
    [--no-light]

One frame per process (a farm splitting frames): --start N --end N --render N N. The simulation itself is
sequential: a process finds the frames other processes have finished and simulates only the rest.
"""

import argparse
import sys

import addon_utils
import bpy


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("blend", help=".blend with Snow Sprays (Add Snow Spray)")
    parser.add_argument("--start", type=int, help="first frame whose light is baked (default: the spray's first)")
    parser.add_argument("--end", type=int, required=True, help="last frame to simulate and light")
    parser.add_argument("--no-light", action="store_true", help="simulate only: no baked light")
    parser.add_argument("--render", type=int, nargs=2, metavar=("FIRST", "LAST"), help="frames to render")
    return parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])


def main():
    args = parse_args()
    addon_utils.enable("firn", default_set=True, persistent=True)  # stays through the file load
    bpy.ops.wm.open_mainfile(filepath=args.blend)  # after enabling Firn: its load handlers find the cache
    frames = {"frame_end": args.end} if args.start is None else {"frame_start": args.start, "frame_end": args.end}
    if bpy.ops.firn.bake_sequence(light=not args.no_light, **frames) != {"FINISHED"}:
        sys.exit("firn: Bake Sequence failed")
    if args.render:
        scene = bpy.context.scene
        scene.frame_start, scene.frame_end = args.render
        bpy.ops.render.render(animation=True)


main()
