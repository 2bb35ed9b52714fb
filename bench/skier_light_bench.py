"""The skier sample's lumps baked per frame (docs/spray.md "Light", the skier paragraph) against the core's Monte
Carlo of the same scene: blend_samples/skier.py's scene built headless in Blender (its own functions, no render),
frames 1..FRAMES simulated, the last one baked by Bake Sequence (DRAFT, as the sample), and that frame's bake
inputs as spray/light.py gathers them (sun, Nishita sky map, occluders: slope, body) dumped once into --folder
(inputs.json + inputs.npz beside the frame's files). Then, in plain Python: the lumps baked again from those inputs
plus the snow's surface mesh one voxel under its surface (white-sky albedo), as Bake Sequence bakes them (the
rebake must equal Bake Sequence's lit_spray file), rendered from the side (orthographic from -y, the lumps'
2..98 % extent, 4 x 4-pixel blocks) against firncore.monte_carlo_radiance (all orders, exact phase function) of
the same lumps, occluders and light, two seeds (their difference: the reference's own noise); then sun only and
sky only (each baked and referenced alone). Bake times are processor seconds (stats["cpu_seconds"]); the
references are kept in the folder (same seeds: the same values) for the next run.

PYTHONPATH=build/python /usr/bin/python3 bench/skier_light_bench.py [--folder /tmp/firn_skier_light]
    [--frames 8] [--samples 64] [--pixels 48] [--quality DRAFT] [--no-split]
(the first run calls bench/run.sh on this file to build the frame: some 2 minutes)
"""

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from block_compare import compare  # noqa: E402  (bench/ on the path when Blender runs this file)


def side_view(positions, n):
    """The orthographic view from -y over the lumps (2nd to 98th percentile of their positions in x and z, m):
    the pixel grid X (n x n // 2), the rays' origins and directions, and the extent (x0, x1, z0, z1)."""
    (x0, x1), (z0, z1) = np.percentile(positions[:, 0], [2, 98]), np.percentile(positions[:, 2], [2, 98])
    X, Z = np.meshgrid(np.linspace(x0, x1, n), np.linspace(z0, z1, n // 2))
    origins = np.stack([X.ravel(), np.full(X.size, -3.0), Z.ravel()], 1)
    return X, origins, np.tile([0.0, 1.0, 0.0], (X.size, 1)), (x0, x1, z0, z1)


def build(folder, frames):
    """In Blender: the sample's scene, frames 1..frames simulated and the last baked; its bake inputs dumped."""
    import bpy

    sample = os.path.join(HERE, "..", "blend_samples", "skier.py")
    source = open(sample).read().rstrip()
    assert source.endswith("main()")
    ns = {"__file__": sample, "__name__": "skier_sample"}
    exec(compile(source[:-len("main()")], sample, "exec"), ns)
    common = ns["common"]
    os.makedirs(folder, exist_ok=True)
    start = time.time()
    scene, ground, skis = ns["build_scene"](frames)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(folder, "skier.blend"))  # its cache folder beside it
    snow = common.add_snow([ground], depth=ns["SNOW_DEPTH"], spacing=0.05, voxel_size=0.02, seed=2)
    spray = ns["add_spray"](snow, skis, frames)
    print("spray:", spray.firn.spray.summary, f"({time.time() - start:.0f} s)", flush=True)
    assert bpy.ops.firn.bake_sequence(frame_start=frames, frame_end=frames, quality="DRAFT") == {"FINISHED"}
    bpy.ops.wm.save_mainfile()

    from firn.bake import inputs as bake_inputs
    from firn.spray import light, operators as spray_ops
    job = light.gather(bpy.context, spray, spray_ops._tracks_of(spray), [frames], "DRAFT", 0)[0]
    inputs = job["inputs"]
    if inputs.sky is None:
        world = bake_inputs.world_request(scene, [inputs.frame])
        world.prepare(cancelled=lambda: False)
        bake_inputs.add_world_light(inputs, world)
    arrays = {}
    meta = {"paths": list(job["paths"]), "outputs": list(job["outputs"]), "frame": frames,
            "optics": [job["optics"].extinction_per_density, list(job["optics"].albedo), job["optics"].g],
            "suns": [[list(s.direction), list(s.irradiance), s.angular_diameter] for s in inputs.suns],
            "sky_radiance": list(inputs.sky.radiance), "occluders": []}
    if inputs.sky.map is not None:
        arrays["sky_map"] = np.asarray(inputs.sky.map, np.float32)
    for i, o in enumerate(inputs.occluders):
        arrays[f"occ{i}_v"], arrays[f"occ{i}_t"] = np.asarray(o.vertices, np.float32), np.asarray(o.triangles, np.uint32)
        meta["occluders"].append([o.name, list(o.albedo), len(o.triangles)])
    np.savez(os.path.join(folder, "inputs.npz"), **arrays)
    with open(os.path.join(folder, "inputs.json.tmp"), "w") as f:
        json.dump(meta, f, indent=1)
    os.replace(os.path.join(folder, "inputs.json.tmp"), os.path.join(folder, "inputs.json"))
    print(f"frame {frames} built and dumped to {folder} ({time.time() - start:.0f} s)")


def measure(args):
    import firncore

    folder = os.path.abspath(args.folder)
    if not os.path.exists(os.path.join(folder, "inputs.json")):
        subprocess.run([os.path.join(HERE, "run.sh"), os.path.abspath(__file__), "--", "--build", folder,
                        "--frames", str(args.frames)], check=True)
        if not os.path.exists(os.path.join(folder, "inputs.json")):
            sys.exit(f"building the frame in Blender wrote no {folder}/inputs.json (see its output above)")
    meta = json.load(open(os.path.join(folder, "inputs.json")))
    arrays = np.load(os.path.join(folder, "inputs.npz"))
    snow, spray = meta["paths"]
    extinction, albedo, g = meta["optics"]
    optics = firncore.VolumeOptics(extinction, tuple(albedo), g)
    suns = [firncore.SunLight(tuple(d), tuple(i), diameter) for d, i, diameter in meta["suns"]]
    sky = firncore.Sky(radiance=tuple(meta["sky_radiance"]), map=arrays["sky_map"] if "sky_map" in arrays else None)
    dark = firncore.Sky(radiance=(0.0, 0.0, 0.0))
    occluders = [(arrays[f"occ{i}_v"], arrays[f"occ{i}_t"], tuple(o[1])) for i, o in enumerate(meta["occluders"])]
    voxel = firncore.grid_statistics(snow, "surface")["voxel_size"]
    surface = firncore.snow_surface_mesh(snow, adaptivity=0.5, isovalue=-voxel)
    occluders.append((*surface, optics.white_sky_albedo))
    lumps = firncore.grid_statistics(spray, "density")
    print(f"frame {meta['frame']}: {lumps['active_voxels']} lump voxels of {lumps['voxel_size'] * 100:.0f} cm; optics "
          f"{extinction:.2f} m^2/kg, g {g:.3f}; occluders {[o[0] for o in meta['occluders']]} + snow surface "
          f"{len(surface[1])} triangles; {firncore.hardware_threads()} threads, load {os.getloadavg()[0]:.1f}")

    positions = np.asarray(firncore.read_spray_state(spray[:-len(".vdb")] + ".state").positions)
    n = args.pixels
    X, origins, directions, (x0, x1, z0, z1) = side_view(positions, n)
    print(f"side view: x {x0:.2f}..{x1:.2f}, z {z0:.2f}..{z1:.2f} m, {n} x {n // 2} pixels, "
          f"reference {args.samples} paths per pixel")
    lights = {"sun and sky": dict(suns=suns, sky=sky)}
    if args.split:
        lights.update({"sun only": dict(suns=suns, sky=dark), "sky only": dict(suns=[], sky=sky)})
    for name, light in lights.items():
        tag = name.replace(" ", "_")
        baked = os.path.join(folder, f"bench_{tag}_{args.quality}{args.source_scale or ''}.vdb")
        stats = firncore.bake(spray, optics, occluders=occluders, quality=args.quality, seed=0, output_path=baked,
                              source_scale=args.source_scale, **light)
        cpu = stats["cpu_seconds"]
        print(f"{name}: bake {args.quality} {sum(cpu.values()):.1f} processor s ("
              + ", ".join(f"{k} {v:.1f}" for k, v in cpu.items()) + f"), traced voxels {stats['traced_voxels']} "
              f"({stats['light_traced_voxels']} light traced), source scale {stats['source_scale']}, load {os.getloadavg()[0]:.1f}", flush=True)
        render = firncore.render_baked(baked, optics, origins, directions, occluders=occluders)
        if name == "sun and sky" and args.quality == "DRAFT":
            file = firncore.render_baked(meta["outputs"][1], optics, origins, directions, occluders=occluders)
            print(f"  Bake Sequence's lit_spray file vs this bake: max |diff| / max "
                  f"{np.abs(file - render).max() / max(render.max(), 1e-30):.1e}")
        references = []
        for seed in (1, 2) if name == "sun and sky" else (1,):
            saved = os.path.join(folder, f"reference_{tag}_{n}_{args.samples}_seed{seed}.npy")
            if not os.path.exists(saved):
                start = time.time()
                mean = firncore.monte_carlo_radiance(spray, optics, origins, directions, occluders=occluders,
                                                     samples=args.samples, seed=seed, **light)[0]
                np.save(saved[:-4] + ".tmp.npy", mean)
                os.replace(saved[:-4] + ".tmp.npy", saved)
                print(f"  reference seed {seed}: {time.time() - start:.0f} s wall, load {os.getloadavg()[0]:.1f}")
            references.append(np.load(saved))
        for seed, reference in zip((1, 2), references):
            compare(f"baked vs reference seed {seed}", render, reference, X.shape, width=36)
        if len(references) > 1:
            compare("reference seed 2 vs seed 1", references[1], references[0], X.shape, width=36)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser()
    parser.add_argument("--folder", default="/tmp/firn_skier_light", help="the built frame and references")
    parser.add_argument("--frames", type=int, default=8, help="frames simulated; the last is measured")
    parser.add_argument("--samples", type=int, default=64, help="Monte Carlo paths per pixel")
    parser.add_argument("--pixels", type=int, default=48, help="columns of the side view (rows: half)")
    parser.add_argument("--quality", default="DRAFT")
    parser.add_argument("--source-scale", type=int, default=0, help="the bake's source_scale (0: its budget's)")
    parser.add_argument("--no-split", dest="split", action="store_false", help="no sun-only and sky-only rows")
    parser.add_argument("--build", default=None, help=argparse.SUPPRESS)  # in Blender: build into this folder
    args = parser.parse_args(argv)
    if args.build:
        build(os.path.abspath(args.build), args.frames)
    else:
        measure(args)


if __name__ == "__main__":
    main()
