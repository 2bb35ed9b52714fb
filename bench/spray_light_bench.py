"""The light of a ski spray's lumps baked per frame (docs/spray.md "Light"): the last frame of a 12-frame ski spray
(the default SpraySettings, seed 5, through a 2 m x 1 m snow layer 15 cm deep at 2 cm voxels), lit by a sun and a
uniform sky, baked as Bake Sequence bakes it (spray/light.py): the tracked snow with the lumps in it as one medium
(firncore.bake_joint), the lumps over the snow's surface mesh (one voxel under the surface: lumps resting in the
groove stay outside it) as an occluder of the snow's white-sky albedo (firncore.bake), against the core's Monte
Carlo of lumps and snow as one medium (firncore.monte_carlo_radiance of firncore.union_density: all orders, exact
Henyey-Greenstein phase function, none of the bake's approximations).

PYTHONPATH=build/python /usr/bin/python3 bench/spray_light_bench.py [--samples 256] [--above-samples 64]
    [--pixels 48] [--adaptivity 0.5] [--folder DIR] [--dense] [--quality FINAL]
Views (orthographic): "side", from -y over the spray above the snow (the lumps alone in view; 4 x 4-pixel blocks
as /work/draft/spraybake/measure.py); "above", looking down on the snow beside and under the spray (the spray's
shadow on the snow; the lumps and the snow in view). Rows besides Bake Sequence's: the lumps' part of the joint
medium's bake (their paths enter the snow: the bake's budget leaves them untraced), the lumps baked alone (no
snow under them: what the bake gave before) and the tracked snow baked alone (what Bake Sequence baked before).
--dense: the skier sample's lumps instead (1 cm voxels; dense()). --quality: the bakes' (DRAFT light traces a quarter
of FINAL's photons: docs/spray.md "Light"). Bake times are processor seconds (stats["cpu_seconds"], all phases):
compare those, as wall seconds vary with the machine's load. The references are kept in the folder (same seeds: the same values) for the next run.
"""

import argparse
import os
import tempfile
import time

import numpy as np

import firncore
from block_compare import compare

FPS = 24.0
FRAMES = 12
OPTICS = firncore.VolumeOptics(8.18, (0.99998,) * 3, 0.89)
SUNS = [firncore.SunLight((0.5, -0.3, 0.81), (3.0, 3.0, 3.0), 0.0093)]
SKY = firncore.Sky(radiance=(0.3, 0.35, 0.45))


def ski_spray(folder, settings):
    """(tracked snow, lumps) files of the spray's last frame."""
    snow = os.path.join(folder, "snow.vdb")
    if not os.path.exists(snow):
        vertices = np.array([[-1, -0.5, 0], [1, -0.5, 0], [1, 0.5, 0], [-1, 0.5, 0]], np.float32)
        firncore.generate_snow_layer(vertices, np.array([[0, 1, 2], [0, 2, 3]], np.uint32), None,
                                     firncore.SnowLayerSettings(depth=0.15, spacing=0.05, voxel_size=0.02, seed=2),
                                     snow)
    emitter = np.zeros((FRAMES, 3, 3))
    emitter[:, 0] = [[-0.6 + 5.0 * f / FPS, 0.0, 0.10] for f in range(FRAMES)]
    emitter[:, 1], emitter[:, 2] = [0.4, 0, 0], [0, 0.05, 0]
    firncore.simulate_spray(snow, [emitter], folder, fps=FPS, first_frame=1, settings=settings)
    tracked = next(path for frame in range(FRAMES, 0, -1)  # the core writes the snow where tracks changed it
                   if os.path.exists(path := firncore.spray_frame_paths(folder, frame)[1]))
    return tracked, firncore.spray_frame_paths(folder, FRAMES)[0]


def view(name, n):
    """(origins, directions, (rows, columns)) of an orthographic view."""
    if name == "side":
        X, Z = np.meshgrid(np.linspace(0.6, 2.2, n), np.linspace(0.16, 0.45, n // 2))
        origins = np.stack([X.ravel(), np.full(X.size, -1.0), Z.ravel()], 1)
        return origins, np.tile([0.0, 1.0, 0.0], (X.size, 1)), X.shape
    X, Y = np.meshgrid(np.linspace(0.2, 1.8, n), np.linspace(-0.45, 0.45, n // 2))
    origins = np.stack([X.ravel(), Y.ravel(), np.full(X.size, 1.0)], 1)
    return origins, np.tile([0.0, 0.0, -1.0], (X.size, 1)), X.shape


def timed(label, bake):
    start = time.time()
    stats = bake()
    cpu = sum(stats["cpu_seconds"].values())
    print(f"  {label:<28} {time.time() - start:6.1f} s wall, {cpu:6.1f} processor s, traced voxels "
          f"{stats['traced_voxels']} ({stats['light_traced_voxels']} light traced, {stats['photons']} photons), "
          f"trace {stats['cpu_seconds']['trace']:.1f} processor s, load {os.getloadavg()[0]:.1f}")


def monte_carlo(saved, medium, origins, directions, samples):
    """The reference radiance (N, 3), kept in `saved` for the next run on the same folder (same seeds)."""
    if os.path.exists(saved):
        return np.load(saved)
    reference, _error = firncore.monte_carlo_radiance(medium, OPTICS, origins, directions, suns=SUNS, sky=SKY,
                                                      samples=samples, seed=1)
    np.save(saved, reference)
    return reference


def dense(args, folder):
    """The skier sample's lumps (blend_samples/skier.py: 1.2 cm lumps on 1 cm voxels) over the snow's surface mesh,
    baked as Bake Sequence bakes them, against the core's Monte Carlo of the same scene (the lumps over that mesh;
    the mesh standing for the snow is measured by the default run), and a second reference of another seed: the
    references' own noise per block."""
    tracked, spray = ski_spray(folder, firncore.SpraySettings(seed=5, lump_radius=0.012, voxel_size=0.01))
    path = lambda name: os.path.join(folder, name)
    voxels = firncore.grid_statistics(spray, "density")["active_voxels"]
    print(f"frame {FRAMES}: lumps {spray}, {voxels} voxels")
    voxel = firncore.grid_statistics(tracked, "surface")["voxel_size"]
    surface = firncore.snow_surface_mesh(tracked, adaptivity=args.adaptivity, isovalue=-voxel)
    occluders = [(*surface, OPTICS.white_sky_albedo)]
    print(f"bake ({args.quality}, seed 0):")
    timed("lumps over the snow surface", lambda: firncore.bake(spray, OPTICS, suns=SUNS, sky=SKY, occluders=occluders,
                                                                output_path=path("lit_spray.vdb"),
                                                                quality=args.quality))
    origins, directions, shape = view("side", args.pixels)
    references = []
    for seed in (1, 2):
        saved = path(f"reference_dense_side_{args.pixels}_{args.samples}" + ("" if seed == 1 else f"_{seed}") + ".npy")
        if not os.path.exists(saved):
            np.save(saved, firncore.monte_carlo_radiance(spray, OPTICS, origins, directions, suns=SUNS, sky=SKY,
                                                         occluders=occluders, samples=args.samples, seed=seed)[0])
        references.append(np.load(saved))
    print(f"side view, {shape[1]} x {shape[0]} pixels, reference {args.samples} paths per pixel:")
    compare("lumps over the snow surface", firncore.render_baked(path("lit_spray.vdb"), OPTICS, origins, directions),
            references[0], shape)
    compare("reference of seed 2", references[1], references[0], shape)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=256, help="Monte Carlo paths per pixel")
    parser.add_argument("--above-samples", type=int, default=64, help="paths per pixel of the view from above")
    parser.add_argument("--adaptivity", type=float, default=0.5, help="of the snow surface the lumps see")
    parser.add_argument("--pixels", type=int, default=48, help="columns of a view (rows: half)")
    parser.add_argument("--folder", default=None, help="keep the files here (default: a temporary folder)")
    parser.add_argument("--dense", action="store_true", help="the skier sample's lumps instead (see dense())")
    parser.add_argument("--quality", default="FINAL", choices=("DRAFT", "FINAL"), help="of every bake")
    args = parser.parse_args()
    folder = args.folder or tempfile.mkdtemp(prefix="firn_spray_light_")
    os.makedirs(folder, exist_ok=True)
    if args.dense:
        return dense(args, folder)
    tracked, spray = ski_spray(folder, firncore.SpraySettings(seed=5))
    path = lambda name: os.path.join(folder, name)
    print(f"frame {FRAMES}: lumps {firncore.spray_frame_paths(folder, FRAMES)[0]}")
    quality = args.quality
    print(f"bakes ({quality}, seed 0):")
    timed("tracked snow, lumps in it", lambda: firncore.bake_joint(
        [tracked, spray], [path("lit_snow.vdb"), None], OPTICS, suns=SUNS, sky=SKY, quality=quality))
    start = time.time()
    voxel = firncore.grid_statistics(tracked, "surface")["voxel_size"]
    surface = firncore.snow_surface_mesh(tracked, adaptivity=args.adaptivity, isovalue=-voxel)
    print(f"  {'snow surface mesh':<28} {time.time() - start:6.1f} s wall, {len(surface[1])} triangles "
          f"(adaptivity {args.adaptivity})")
    timed("lumps over the snow surface", lambda: firncore.bake(
        spray, OPTICS, suns=SUNS, sky=SKY, occluders=[(*surface, OPTICS.white_sky_albedo)],
        output_path=path("lit_spray.vdb"), quality=quality))
    timed("lumps in the joint medium", lambda: firncore.bake_joint(
        [tracked, spray], [None, path("joint_spray.vdb")], OPTICS, suns=SUNS, sky=SKY, quality=quality))
    timed("lumps alone", lambda: firncore.bake(spray, OPTICS, suns=SUNS, sky=SKY, output_path=path("alone.vdb"),
                                               quality=quality))
    timed("tracked snow alone", lambda: firncore.bake(tracked, OPTICS, suns=SUNS, sky=SKY,
                                                       output_path=path("snow_alone.vdb"), quality=quality))
    firncore.union_density([tracked, spray], path("union.vdb"))
    firncore.bake(path("union.vdb"), OPTICS, suns=SUNS, sky=SKY, output_path=path("union_lit.vdb"), quality=quality)
    for name, samples in (("side", args.samples), ("above", args.above_samples)):
        origins, directions, shape = view(name, args.pixels)
        start = time.time()
        reference = monte_carlo(path(f"reference_{name}_{args.pixels}_{samples}.npy"), path("union.vdb"),
                                origins, directions, samples)
        print(f"{name} view, {shape[1]} x {shape[0]} pixels, reference {samples} paths per pixel "
              f"({time.time() - start:.0f} s):")
        drawn = lambda file: firncore.render_baked(path(file), OPTICS, origins, directions)
        if name == "side":  # the lumps alone in view: their file renders by itself
            compare("lumps over the snow surface", drawn("lit_spray.vdb"), reference, shape)
            compare("lumps in the joint medium", drawn("joint_spray.vdb"), reference, shape)
            compare("lumps alone", drawn("alone.vdb"), reference, shape)
        else:  # lumps and snow in view: the union with the joint bake's grids (its snow part is lit_snow.vdb's)
            compare("snow and lumps, one medium", drawn("union_lit.vdb"), reference, shape)
            compare("tracked snow alone", drawn("snow_alone.vdb"), reference, shape)


if __name__ == "__main__":
    main()
