"""The step from the baked grids to the camera under a near lamp (docs/benchmarks.md, lamp-shell).

bench/lamp_terminator.py's ball (ball_grey's snow, here on --voxel m voxels), its --round 24 views, the sun and a
lamp (--lamp, point): the bake, then the same grids rendered (render_baked) in other ways, each against the cached
Monte Carlo (bias of the sums over the seen blocks) and as the ratio lamp / sun of the rendered sums:
  as baked    the grids as written (the renderer's trilinear density and source, each interpolated alone);
  fine copy   the same fields on voxels --fine times smaller (trilinear of trilinear is trilinear: a check that
              the copy changes nothing);
  product     the emission sigma_t S interpolated instead of S: the fine source is tri(rho S) / tri(rho), so the
              source outside the snow (the bake's extended values) weighs nothing;
  snow only   the source interpolated between the voxels with snow alone (the air voxels' extended values unread);
  nearest     the source of the nearest coarse voxel with snow (each voxel's values held constant over it);
  centre      the source on the fine voxels taken from the coarse voxel whose centre is nearest (density as baked).

    PYTHONPATH=build/python:bench python3 bench/lamp_render_step.py [--voxel 0.0125] [--lamp area] [--schemes ...]
"""

import argparse
import dataclasses
import os
import tempfile

import numpy as np
import pyopenvdb

import firncore
from bake_suite import case as suite_case, views, write_density
from lamp_terminator import lamp, on_voxels, reference, round_views

PAD = 3  # coarse voxels around the density's box that the source grids may reach (the bake's ring)


def dense(grid, shape):
    """`grid`'s values on the coarse index box [-PAD, shape + PAD) as an array (..., 3 for a vector grid)."""
    size = tuple(s + 2 * PAD for s in shape)
    out = np.zeros(size + ((3,) if grid.valueTypeName.startswith("vec3") else ()), dtype=np.float32)
    grid.copyToArray(out, ijk=(-PAD, -PAD, -PAD))
    return out.astype(np.float64)


def trilinear(values, x):
    """`values` (a dense array from `dense`) at coarse index positions x (N, 3); zero outside."""
    p = x + PAD
    f = np.floor(p).astype(int)
    t = p - f
    out = np.zeros((len(x),) + values.shape[3:])
    n = np.array(values.shape[:3])
    for corner in range(8):
        o = np.array([(corner >> a) & 1 for a in range(3)])
        c = f + o
        inside = np.all((c >= 0) & (c < n), axis=1)
        w = np.prod(np.where(o == 1, t, 1.0 - t), axis=1) * inside
        cc = np.clip(c, 0, n - 1)
        v = values[cc[:, 0], cc[:, 1], cc[:, 2]]
        out += (w.reshape((-1,) + (1,) * (v.ndim - 1))) * v
    return out


def nearest_with_snow(rho, x):
    """The coarse voxel (index into the padded arrays) with snow nearest each position x (N, 3)."""
    snow = np.argwhere(rho > 0)
    near = np.rint(x + PAD).astype(int)
    d2 = ((near[:, None, :] - snow[None, :, :]) ** 2).sum(axis=2)
    return snow[d2.argmin(axis=1)]


def shifted(voxel):
    """The transform of voxels of `voxel` m as Firn writes them (firn_half_voxel_shift: moved by -voxel / 2)."""
    s = voxel
    return pyopenvdb.createLinearTransform([[s, 0, 0, 0], [0, s, 0, 0], [0, 0, s, 0], [-s / 2, -s / 2, -s / 2, 1]])


def refined(path, out_path, shape, voxel, fine, scheme):
    """Writes `path`'s density and source grids on voxels `fine` times smaller with the source taken by `scheme`."""
    grids, meta = pyopenvdb.readAll(path)
    by_name = {g.name: g for g in grids}
    rho = dense(by_name["density"], shape)
    names = ["firn_source", "firn_source_x", "firn_source_y", "firn_source_z", "firn_source_peak",
             "firn_source_peak_l1"]
    source = {n: dense(by_name[n], shape) for n in names}
    axes = [np.arange(-PAD * fine, (s + PAD - 1) * fine + 1) for s in shape]
    j = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    x = j / fine  # coarse index positions of the fine voxels
    rho_f = trilinear(rho, x)
    if scheme == "product":
        emission = {n: trilinear(rho[..., None] * source[n], x) for n in names}
        values = {n: np.where(rho_f[:, None] > 0, emission[n] / np.maximum(rho_f[:, None], 1e-30), 0.0)
                  for n in names}
    elif scheme == "snow only":
        snow = (rho > 0).astype(float)
        weight = trilinear(snow, x)[:, None]
        values = {n: np.where(weight > 0, trilinear(snow[..., None] * source[n], x) / np.maximum(weight, 1e-30), 0.0)
                  for n in names}
    elif scheme == "nearest":
        k = nearest_with_snow(rho, x)
        values = {n: source[n][k[:, 0], k[:, 1], k[:, 2]] for n in names}
    elif scheme == "centre":
        k = np.clip(np.rint(x + PAD).astype(int), 0, np.array(rho.shape) - 1)
        values = {n: source[n][k[:, 0], k[:, 1], k[:, 2]] for n in names}
    else:
        values = {n: trilinear(source[n], x) for n in names}
    size = tuple(len(a) for a in axes)
    origin = tuple(int(a[0]) for a in axes)
    written = []
    for g in grids:
        if g.name == "density":
            h = pyopenvdb.FloatGrid()
            h.copyFromArray(rho_f.reshape(size).astype(np.float32), ijk=origin, tolerance=0)
        elif g.name in values:
            h = pyopenvdb.Vec3SGrid()
            vec3 = values[g.name].reshape(size + (3,)).astype(np.float32)
            h.copyFromArray(vec3, ijk=origin, tolerance=(0.0, 0.0, 0.0))
        else:
            continue
        h.name = g.name
        h.metadata = g.metadata
        h.transform = shifted(voxel / fine)
        written.append(h)
    pyopenvdb.write(out_path, grids=written, metadata=meta)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--voxel", type=float, default=0.0125, help="m: ball_grey's ball on these voxels")
    parser.add_argument("--fine", type=int, default=4, help="the fine copies' voxels per coarse voxel")
    parser.add_argument("--samples", type=int, default=1024, help="the reference's paths per block")
    parser.add_argument("--lamp", default="point", help="the lamp set against the sun: point, spot or area")
    parser.add_argument("--schemes", default="as baked,fine copy,product,snow only,nearest,centre")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_lamp_terminator"))
    args = parser.parse_args()
    case = on_voxels(suite_case("ball_grey"), args.voxel)
    case = dataclasses.replace(case, views=round_views(24))
    case.sky = 0.0
    origins, directions, tau = views(case)
    seen = tau >= 1.0
    schemes = args.schemes.split(",")
    sums = {}
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "ball.vdb")
        write_density(path, case.density, case.voxel)
        for kind in ("sun", args.lamp):
            mean, _ = reference(case, kind, path, origins, directions, args.samples, args.cache)
            light = lamp(kind, case)
            firncore.bake(path, case.optics, suns=case.suns() if light is None else [],
                          lamps=[] if light is None else [light], quality="FINAL", seed=0)
            for scheme in schemes:
                file = path
                if scheme != "as baked":
                    file = os.path.join(folder, "fine.vdb")
                    refined(path, file, case.density.shape, case.voxel, args.fine,
                            "trilinear" if scheme == "fine copy" else scheme)
                baked = firncore.render_baked(file, case.optics, origins, directions)
                sums[kind, scheme] = (baked[seen, 1].sum(), mean[seen, 1].sum())
            write_density(path, case.density, case.voxel)
    print(f"ball_grey on {args.voxel * 100:g} cm voxels, 24 views over the sphere, channel G; "
          f"fine copies 1/{args.fine}")
    print(f"  {'render of the grids':<22} {'sun bias':>9} {args.lamp + ' bias':>11} {args.lamp + ' / sun':>12} "
          f"{'(MC)':>7}")
    for scheme in schemes:
        (bs, ms), (bp, mp) = sums["sun", scheme], sums[args.lamp, scheme]
        print(f"  {scheme:<22} {100 * (bs / ms - 1):+8.1f}% {100 * (bp / mp - 1):+10.1f}% {bp / bs:12.4f} "
              f"{mp / ms:7.4f}")


if __name__ == "__main__":
    main()
