"""Thin snow lying on the ground, baked against the core's Monte Carlo as bench/bake_suite.py measures its cases
(docs/benchmarks.md, "plate-err": what surface normals beside an occluder change).

bumpy_plate's snow (tau 15 per voxel, omega 0.999, g 0.7; sun 30 degrees high and the suite's sky) on a grey ground
(albedo 0.5): flat layers 1, 2, 3 and 6 voxels thick (16 x 16 voxels of 1 cm, the ground between the empty row
under them and their lowest voxel) and bumpy layers 2 +- 1 and 3 +- 1.5 voxels thick (24 x 24, bake_suite.bumpy);
views (0, 60), (180, 50), (90, 70), 8 x 8 blocks each. References (--samples paths) are cached in --cache.
--one-voxel: layers one to three voxels thick over 6 to 24 voxels, 1.5 to 15 optical depths per voxel, on the grey
ground, a black one and none (docs/benchmarks.md, "one-voxel").
--float: the one-voxel layer floating (no ground), 16 x 16 and 6 x 6 voxels at 15, 6, 3 and 2 optical depths per voxel,
seen from above and from below (azimuths as VIEWS, elevations negated), and under the sun alone and the sky alone
(docs/benchmarks.md, "float-voxel").

    PYTHONPATH=build/python /usr/bin/python3 bench/snow_on_ground_bench.py [--samples 1024] [--cache DIR]
        [--one-voxel | --float]
"""

import argparse
import os
import tempfile

import bake_suite as bs

H = 0.01  # m
VIEWS = [(0, 60), (180, 50), (90, 70)]


def shapes():
    """(name, density, ground height in m, ground albedo or None, optical depth per voxel)."""
    for layers in (1, 2, 3, 6):
        yield f"flat {layers}", bs.slab(16, layers) * 300.0, 1.5 * H, 0.5, 15.0
    for depth, amplitude in ((2, 1.0), (3, 1.5)):
        yield f"bumpy {depth} +- {amplitude}", bs.bumpy(24, depth, amplitude) * 300.0, 0.5 * H, 0.5, 15.0


def one_voxel_shapes():
    for tau in (15.0, 6.0, 3.0, 1.5):
        for albedo in (0.5, None, 0.0):
            yield f"1 tau {tau:g} {albedo}", bs.slab(16, 1) * 300.0, 1.5 * H, albedo, tau
    for width, layers in ((6, 1), (24, 1), (12, 2), (10, 3)):
        for albedo in (0.5, None):
            yield f"{width}x{width}x{layers} {albedo}", bs.slab(width, layers) * 300.0, 1.5 * H, albedo, 15.0


def float_shapes():
    """(name, density, optical depth per voxel, views, sun W/m^2, sky W/m^2/sr)."""
    below = [(azimuth, -elevation) for azimuth, elevation in VIEWS]
    for width in (16, 6):
        for tau in (15.0, 6.0, 3.0, 2.0):
            for side, views in (("above", VIEWS), ("below", below)):
                yield f"{width}x{width}x1 tau {tau:g} {side}", bs.slab(width, 1) * 300.0, tau, views, 1.0, 0.05
    for light, sun, sky in (("sun", 1.0, 0.0), ("sky", 0.0, 0.05)):
        yield f"16x16x1 tau 15 {light}", bs.slab(16, 1) * 300.0, 15.0, VIEWS, sun, sky


def report(name, r):
    print(f"{name:<24} mean {100 * r['mean']:5.1f} %  worst {100 * r['worst_signed']:+4.0f} %  bias "
          f"{100 * r['bias']:+5.1f} %  views " + ", ".join(f"{100 * b:+.1f}" for b in r["view_bias"]) +
          f"  noise {100 * r['noise']:.1f} %  traced {r['traced']}  trace {r['trace_cpu_s']:.2f} processor s",
          flush=True)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_snow_on_ground"))
    parser.add_argument("--one-voxel", action="store_true")
    parser.add_argument("--float", action="store_true")
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    if args.float:
        for name, density, tau, views, sun, sky in float_shapes():
            case = bs.Case(name.replace(" ", "_"), name, density, H, tau / H, 300.0, (0.999,) * 3, 0.7, sun=sun,
                           sky=sky, views=views, pixels=8, samples=args.samples)
            with tempfile.TemporaryDirectory() as folder:
                report(name, bs.run_case(case, folder, cache=args.cache))
        return
    for name, density, height, albedo, tau in (one_voxel_shapes() if args.one_voxel else shapes()):
        ground = [] if albedo is None else [bs.plate(-1.0, 2.0, -1.0, 2.0, height, (albedo,) * 3)]
        case = bs.Case(name.replace(" ", "_"), name, density, H, tau / H, 300.0, (0.999,) * 3, 0.7, views=VIEWS,
                       pixels=8, occluders=ground, samples=args.samples)
        with tempfile.TemporaryDirectory() as folder:
            r = bs.run_case(case, folder, cache=args.cache)
        report(name, r)


if __name__ == "__main__":
    main()
