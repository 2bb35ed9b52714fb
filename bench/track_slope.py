"""Tracks on a slope (issue 14): one frame's simulation where the snow is flat and where it is a 20 degree slope,
in one run. Few lumps are thrown, so the tracks' cut (spray/tracks.h) is most of the time.

PYTHONPATH=build/python /usr/bin/python3 bench/track_slope.py [--slopes 0,20] [--threads 2] [--voxel 0.02]
A 6 m x 3 m layer 30 cm deep, tilted down +x; two 1.6 m x 0.1 m skis 5 cm under its top slide 0.33 m a frame
down the lower part of the slope for 4 frames (24 fps, 4 sub-steps). Until stop 99 each box of a track rose to the
whole snow's top: on the slope the skis' boxes were 0.7 m tall and a frame took 3.4x the flat one's time.
"""

import argparse
import pathlib
import shutil
import tempfile
import time

import numpy as np

import firncore

FPS = 24.0


def tilt(slope_deg):
    """The map from the slope's plane (x down the slope, z along its normal) to the world, tilted about y."""
    a = np.radians(slope_deg)
    m = np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])
    return lambda p: m @ np.asarray(p, float)


def frame_seconds(slope_deg, voxel, frames=5):
    work = pathlib.Path(tempfile.mkdtemp(prefix="firn_track_slope_"))
    try:
        to_world = tilt(slope_deg)
        corners = [to_world(p) for p in ([-3, -1.5, 0], [3, -1.5, 0], [3, 1.5, 0], [-3, 1.5, 0])]
        settings = firncore.SnowLayerSettings(depth=0.3, spacing=0.06, voxel_size=voxel, seed=1)
        firncore.generate_snow_layer(np.array(corners, np.float32), np.array([[0, 1, 2], [0, 2, 3]], np.uint32), None,
                                     settings, str(work / "snow.vdb"))
        skis = []
        for side in (-0.15, 0.15):
            e = np.zeros((frames, 3, 3))
            for f in range(frames):
                e[f] = [to_world([1.5 + 8.0 * f / FPS, side, 0.25]), to_world([0.8, 0, 0]), to_world([0, 0.05, 0])]
            skis.append(e)
        start = time.perf_counter()
        run = firncore.simulate_spray(str(work / "snow.vdb"), skis, str(work / "frames"), fps=FPS,
                                      settings=firncore.SpraySettings(rate=2000.0, seed=1, substeps=4))
        return (time.perf_counter() - start) / (frames - 1), run["seconds"]["simulate"] / (frames - 1)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slopes", default="0,20", help="degrees, comma-separated; the first is the reference")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--voxel", type=float, default=0.02, help="m")
    args = parser.parse_args()
    firncore.set_thread_count(args.threads)
    print(f"{'slope':>6} {'s a frame':>10} {'simulate':>9} {'/ first':>8}")
    first = None
    for slope in (float(s) for s in args.slopes.split(",")):
        total, simulate = frame_seconds(slope, args.voxel)
        first = first or total
        print(f"{slope:5.0f}° {total:10.3f} {simulate:9.3f} {total / first:7.2f}x")


if __name__ == "__main__":
    main()
