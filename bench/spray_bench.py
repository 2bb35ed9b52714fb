"""Snow thrown by moving objects (issue 14): the time of one frame (simulation + the frame's VDB files) with about
100,000 lumps in the scene, and how it splits into simulate / rasterize / write. Goal: <= 1 s a frame on 2 cores.

PYTHONPATH=build/python /usr/bin/python3 bench/spray_bench.py [--lumps 100000] [--threads 2] [--voxel 0.02]
Two skis cross a 6 m x 3 m snow layer 30 cm deep; the emission rate is set so that the first frame, where both
skis start in fresh snow, throws about 0.9 x --lumps lumps; later frames add fewer, and splits add more (the lumps
stay where they land: deposit). Each frame is one call of simulate_spray on the sequence made one frame
longer, which resumes after the frame before (the state files), so each call's timings are one frame's. Timings
vary with the machine's load; the lumps and files are seeded and repeat exactly.
"""

import argparse
import pathlib
import shutil
import tempfile
import time

import numpy as np

import firncore

FPS = 24.0


def snow_layer(path, voxel):
    vertices = np.array([[-3, -1.5, 0], [3, -1.5, 0], [3, 1.5, 0], [-3, 1.5, 0]], np.float32)
    settings = firncore.SnowLayerSettings(depth=0.3, spacing=0.06, voxel_size=voxel, seed=1)
    info = firncore.generate_snow_layer(vertices, np.array([[0, 1, 2], [0, 2, 3]], np.uint32), None, settings, path)
    return info["active_voxels"]


def skis(frames):
    """Two 1.6 m x 0.1 m skis, 0.3 m apart, 5 cm into the snow, sliding along x at 8 m/s, turning gently."""
    out = []
    for side in (-0.15, 0.15):
        e = np.zeros((frames, 3, 3))
        for f in range(frames):
            t = f / FPS
            heading = 0.3 * np.sin(2.0 * t)
            along = np.array([np.cos(heading), np.sin(heading), 0.0])
            across = np.array([-along[1], along[0], 0.0])
            e[f, 0] = np.array([-2.2 + 8.0 * t, 0.3 * np.sin(2.0 * t), 0.25]) + side * across
            e[f, 1] = 0.8 * along
            e[f, 2] = 0.05 * across
        out.append(e)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lumps", type=int, default=100000, help="lumps in the scene after the first frame")
    parser.add_argument("--frames", type=int, default=6, help="frames")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--voxel", type=float, default=0.02, help="m, the snow's and the spray's voxel")
    args = parser.parse_args()
    firncore.set_thread_count(args.threads)
    work = pathlib.Path(tempfile.mkdtemp(prefix="firn_spray_bench_"))
    try:
        voxels = snow_layer(str(work / "snow.vdb"), args.voxel)
        # Measured: the first frame throws 0.108 lumps per unit of rate (lumps/m^3; 1.1e-3 m^3 of fresh snow swept).
        rate = 0.9 * args.lumps / 0.108
        settings = firncore.SpraySettings(rate=rate, seed=1, substeps=4)
        print(f"snow: 6 m x 3 m x 0.3 m, {voxels:,} voxels of {args.voxel * 100:.0f} cm; "
              f"{args.threads} threads; emission rate {rate:,.0f} lumps/m^3")
        print(f"{'frame':>5} {'lumps':>8} {'flying':>7} {'total s':>8} {'simulate':>9} {'rasterize':>10} {'write':>7}")
        totals = []
        for frames in range(2, args.frames + 1):
            start = time.perf_counter()
            run = firncore.simulate_spray(str(work / "snow.vdb"), [e[:frames] for e in skis(frames)],
                                          str(work / "frames"), fps=FPS, settings=settings)
            seconds = time.perf_counter() - start
            s = run["seconds"]
            lumps = run["flying"] + run["resting"]
            totals.append((lumps, seconds))
            print(f"{frames:5d} {lumps:8,} {run['flying']:7,} {seconds:8.2f} {s['simulate']:9.2f} "
                  f"{s['rasterize']:10.2f} {s['write']:7.2f}")
        near = [seconds for lumps, seconds in totals if 0.8 * args.lumps <= lumps <= 1.5 * args.lumps]
        if near:
            print(f"frames with {0.8 * args.lumps:,.0f} to {1.5 * args.lumps:,.0f} lumps: {np.mean(near):.2f} s a frame "
                  f"on average (goal <= 1 s), including reading the snow and the state each call resumes from")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
