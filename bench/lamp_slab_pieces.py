"""A large, low area lamp over a flat slab: its pieces meet the top at every cosine, some grazing (mu0 < 0.4, whose
light the ramp scatters: beamsInRamp) and some taken by the surface; the bake against the core's Monte Carlo from
five views (docs/benchmarks.md, area-pieces).

The slab is bake_suite.slab(40, 6) (1 cm voxels, 40 x 40 x 6 cm) of grey snow (omega 0.9, g 0.6, 5 per cm) or
ball_issue's (0.98, 0.85, 10 per cm). Lights: a 60 x 60 cm square or a 60 cm disc facing down 5 cm over the top,
its centre over the slab's +x edge (36 pieces: the top under it sees them at mu0 from 0.08 to 1), or a point lamp
5 cm up 25 cm beside the middle (mu0 0.2 at the middle), or a sun ("sun20": 20 degrees up from the lamps' side, the
suns' rule for one beam to compare with; docs/benchmarks.md, peak-split). Each gives 1 W/m^2 (green) on the top's
middle. Rays aim at an 11 x 11 grid of points on the top (every 3 cm within 15 cm of the middle) from azimuths 0, 90,
180 and 270 degrees (0: from +x, the lamp's side) at 30 degrees elevation and from straight above. Per view: baked /
Monte Carlo.

    PYTHONPATH=build/python python3 bench/lamp_slab_pieces.py [--snow grey|issue] [--lights square,disk,point,sun20]
        [--samples 1024] [--lamp-samples N]  (points of the lamp per beam, the bake's sun_samples; 0: the preset's)
        [--emission-seams]  (the baked emission's jumps across leaf (8-voxel) boundaries against those within)
"""

import argparse
import math
import os
import tempfile

import numpy as np

import firncore
import bake_suite

SNOWS = {"grey": (0.9, 0.6, 5.0), "issue": (0.98, 0.85, 10.0)}  # omega, g, optical depth per cm
VOXEL = 0.01  # m
VIEWS = [(0, 30), (90, 30), (180, 30), (270, 30), (0, 90)]  # azimuth, elevation (degrees) the camera looks from


def light(kind, top):
    """Lamp `kind` over the slab whose top's middle is `top` (m), 1 W/m^2 (green) there; "sunE": a sun E degrees up
    from the lamps' side (+x), 1 W/m^2 on the top (the suns' rule, one beam compared like with like)."""
    if kind.startswith("sun"):
        e = math.radians(float(kind[3:]))
        return firncore.SunLight((math.cos(e), 0.0, math.sin(e)), (1.0 / math.sin(e),) * 3, 0.0093)

    def made(e):
        if kind == "point":
            return firncore.Lamp("POINT", tuple(top + [0.25, 0.0, 0.05]), (e,) * 3)
        shape = {"square": "RECTANGLE", "disk": "ELLIPSE"}[kind]
        return firncore.Lamp(shape, tuple(top + [0.2, 0.0, 0.05]), (e,) * 3, axis=(0.0, 0.0, -1.0),
                             tangent=(1.0, 0.0, 0.0), size=(0.6, 0.6))
    unit = made(1.0).irradiance(tuple(top), (0.0, 0.0, 1.0), samples=20000, seed=1)[1]
    return made(1.0 / unit)


def lights(light):
    """The keyword arguments that light `light` (a sun or a lamp) the core's calls."""
    return {"suns": [light]} if isinstance(light, firncore.SunLight) else {"lamps": [light]}


def rays(top):
    offsets = np.arange(-5, 6) * 0.03
    points = np.array([top + [x, y, 0.0] for x in offsets for y in offsets])
    origins, directions = [], []
    for azimuth, elevation in VIEWS:
        a, e = math.radians(azimuth), math.radians(elevation)
        view = -np.array([math.cos(a) * math.cos(e), math.sin(a) * math.cos(e), math.sin(e)])
        origins.append(points - 0.5 * view)
        directions.append(np.tile(view, (len(points), 1)))
    return np.concatenate(origins), np.concatenate(directions), len(points)


def slab_scene(folder, snow):
    """The slab written to `folder`: (its path, optics, the top's middle (m))."""
    omega, g, tau = SNOWS[snow]
    density = bake_suite.slab(40, 6) * 100.0
    path = os.path.join(folder, "slab.vdb")
    bake_suite.write_density(path, density, VOXEL)
    top = bake_suite.slab_top(density, 6, VOXEL) + [0.0, 0.0, VOXEL / 2]
    return path, firncore.VolumeOptics(tau / VOXEL / 100.0, (omega,) * 3, g), top


def measure(folder, snow, kind, samples, cache=None, lamp_samples=0):
    """The bake under light `kind` against the Monte Carlo (`samples` paths per ray; cached in folder `cache`, None:
    not cached): (bias, per view bias, mean |relative error|), green."""
    path, optics, top = slab_scene(folder, snow)
    lamp = light(kind, top)
    origins, directions, per_view = rays(top)
    file = os.path.join(cache, f"{snow}_{kind}_{samples}.npy") if cache else None
    if file and os.path.exists(file):
        reference = np.load(file)
    else:
        reference, _ = firncore.monte_carlo_radiance(path, optics, origins, directions, **lights(lamp),
                                                     samples=samples, seed=11)
        if file:
            np.save(file, reference)
    firncore.bake(path, optics, **lights(lamp), quality="FINAL", seed=0, sun_samples=lamp_samples)
    baked = firncore.render_baked(path, optics, origins, directions)
    b, r = baked[:, 1].reshape(len(VIEWS), per_view), reference[:, 1].reshape(len(VIEWS), per_view)
    return b.sum() / r.sum() - 1.0, b.sum(axis=1) / r.sum(axis=1) - 1.0, np.mean(np.abs(b / r - 1.0))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--snow", default="grey", choices=sorted(SNOWS))
    parser.add_argument("--lights", default="square,disk,point")
    parser.add_argument("--samples", type=int, default=1024)
    parser.add_argument("--lamp-samples", type=int, default=0)
    parser.add_argument("--emission-seams", action="store_true")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_lamp_slab_pieces"))
    args = parser.parse_args()
    os.makedirs(args.cache, exist_ok=True)
    for kind in args.lights.split(","):
        if args.emission_seams:
            path, optics, top = slab_scene(args.cache, args.snow)
            seams(path, optics, light(kind, top), args.lamp_samples, kind)
            continue
        bias, views, error = measure(args.cache, args.snow, kind, args.samples, args.cache, args.lamp_samples)
        per = " ".join(f"{100 * v:+6.1f}" for v in views)
        print(f"{args.snow:5s} {kind:6s} bias {100 * bias:+6.1f} %   per view {per} %   mean |err| {100 * error:5.1f} %")


def seams(path, optics, lamp, lamp_samples, kind):
    """The baked emission (l0, green) along x, layer by layer, 3 voxels or more inside the slab's sides: the mean
    relative |jump| between neighbours across a leaf boundary (x = 0 mod 8) against that between neighbours within a
    leaf. The slab's top layer is z 7, the ramp above it z 8."""
    import pyopenvdb
    out = path + ".baked.vdb"
    firncore.bake(path, optics, lamps=[lamp], quality="FINAL", seed=0, sun_samples=lamp_samples, output_path=out)
    grid = pyopenvdb.read(out, firncore.BAKED_GRID_NAMES[0])
    lo, hi = grid.evalActiveVoxelBoundingBox()
    values = np.zeros(tuple(np.array(hi) - np.array(lo) + 1) + (3,), np.float32)
    grid.copyToArray(values, ijk=lo)
    for z in range(values.shape[2]):
        layer = values[:, :, z, 1]
        if layer.max() <= 0.0:
            continue
        jumps = np.abs(np.diff(layer, axis=0)) / np.maximum(0.5 * (layer[1:] + layer[:-1]), 1e-12)
        across = (np.arange(lo[0] + 1, hi[0] + 1) % 8) == 0  # the jump from voxel x-1 to x crosses a boundary
        x, y = np.arange(lo[0] + 1, hi[0] + 1)[:, None], np.arange(lo[1], hi[1] + 1)[None, :]
        inside = (x >= 2 + 3) & (x < 2 + 40 - 3) & (y >= 2 + 3) & (y < 2 + 40 - 3)  # 3 voxels off the slab's sides
        lit = (layer[1:] > 0) & (layer[:-1] > 0) & inside
        a, w = jumps[across[:, None] & lit], jumps[~across[:, None] & lit]
        if len(a) and len(w):
            print(f"{kind:6s} samples {lamp_samples or 'preset'} z {lo[2] + z:3d}: |jump| across leaves "
                  f"{100 * a.mean():6.2f} %, within {100 * w.mean():6.2f} %  (ratio {a.mean() / w.mean():5.2f})")


if __name__ == "__main__":
    main()
