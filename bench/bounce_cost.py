"""What Scatter Thin Snow's floor of Cycles volume bounces costs (docs/benchmarks.md, tidy-63): the same renders at
each of `--bounces` (volume and total bounces both set so, as scatter_render_settings sets them), the same Cycles
seed, in rounds whose order turns (the shared machine's load drifts alike over every limit), on
- the suite's cases (`--cases`; bench/thin_scatter_cycles.py's scene: the add-on's mixed material BAKED_SCATTER,
  unclamped, step rate `--step-rate`, every view at `--samples`), their brightness the sum of the blocks of optical
  depth >= 1 over the first limit's;
- the demo's scene (blend_samples/car_under_snow.py, its snow baked FINAL with Scatter Thin Snow on, as
  scripts/demo.sh renders it) at `--demo-width` pixels and `--demo-samples`, its brightness the PNG's mean.
Time: Cycles' wall seconds and this process's processor seconds (Cycles' threads) per render; per round each
limit's processor seconds over the first limit's (paired), their mean and spread over the rounds.

    bench/run.sh bench/bounce_cost.py -- [--bounces 16,24,32] [--rounds 3] [--cases ball_thin,spray_lumps]
        [--samples 64] [--step-rate 0.05] [--demo-width 240] [--demo-samples 32] [--no-demo]
"""

import argparse
import os
import sys
import tempfile
import time
from types import SimpleNamespace

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "blend_samples"))
import sample_common as common  # noqa: E402
import thin_scatter_cycles as thin  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--bounces", default="16,24,32")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--cases", default="ball_thin,spray_lumps")
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples per view of the suite's cases")
    parser.add_argument("--step-rate", type=float, default=0.05, help="the suite's cases' (thin_scatter_cycles)")
    parser.add_argument("--demo-width", type=int, default=240)
    parser.add_argument("--demo-samples", type=int, default=32, help="the demo's own (sample_common.parse_args)")
    parser.add_argument("--no-demo", action="store_true")
    parser.add_argument("--cache", default=os.path.join(tempfile.gettempdir(), "firn_bake_suite"))
    return parser.parse_args(argv)


def timed(render):
    """render() -> brightness, with its wall and processor seconds."""
    wall, cpu = time.perf_counter(), time.process_time()
    brightness = render()
    return brightness, time.perf_counter() - wall, time.process_time() - cpu


def paired_rounds(name, limits, rounds, render):
    """Each round renders at every limit (the order turned by one each round); prints each render and the
    summary: per limit the median seconds, the processor seconds and brightness over the first limit's."""
    scene = bpy.context.scene
    results = {limit: [] for limit in limits}
    for r in range(rounds):
        for limit in limits[r % len(limits):] + limits[:r % len(limits)]:
            scene.cycles.volume_bounces = scene.cycles.max_bounces = limit
            results[limit].append(timed(render))
            brightness, wall, cpu = results[limit][-1]
            print(f"  round {r} bounces {limit:3d}: {wall:6.1f} s wall {cpu:6.1f} s cpu, brightness {brightness:.6g}, "
                  f"load {os.getloadavg()[0]:.1f}", flush=True)
    first = limits[0]
    print(f"{name}: {rounds} rounds; per limit: median wall s, median cpu s, cpu / {first}'s per round "
          f"(mean, min-max), brightness / {first}'s - 1", flush=True)
    for limit in limits:
        wall = np.median([w for _, w, _ in results[limit]])
        cpu = np.median([c for _, _, c in results[limit]])
        ratios = [c / c0 for (_, _, c), (_, _, c0) in zip(results[limit], results[first])]
        brightness = results[limit][0][0] / results[first][0][0] - 1.0
        print(f"  {limit:3d} bounces  {wall:6.1f} s  {cpu:6.1f} s  {np.mean(ratios):.3f} ({min(ratios):.3f}-"
              f"{max(ratios):.3f})  {100 * brightness:+.3f} %", flush=True)


def suite_case(name, limits, args, directory):
    from firn.common.core import firncore

    sys.modules.setdefault("firncore", firncore)  # bake_suite imports it by name, as outside Blender
    import bake_suite

    case = bake_suite.case(name)
    core_path = os.path.join(directory, name + "_core.vdb")
    run = bake_suite.baked_case(case, core_path, args.cache)
    seen = run.tau >= 1.0
    path = os.path.join(directory, name + ".vdb")
    thin.cycles_copy(core_path, path)
    options = SimpleNamespace(step_rate=args.step_rate, bounces=limits[0], threads=2, factor=1)
    snow = thin.scene_for(case, path, options)
    thin.snow_material(snow, case, scatter=True)
    print(f"{name}: {case.what}; views {case.views}; {args.samples} samples per view, step rate {args.step_rate}",
          flush=True)

    def render():
        blocks, _, _ = thin.render_views(case, directory, args.samples, 0, options)
        return float(blocks[seen].sum())

    paired_rounds(name, limits, args.rounds, render)


def demo(limits, args, directory):
    import car_under_snow as car

    scene, targets = car.build_scene()
    snow = car.add_car_snow(targets)
    common.bake([snow])
    print(f"demo (car_under_snow): bake {snow.firn.bake_summary}; Scatter Thin Snow {snow.firn.scatter_thin}; "
          f"bounces after the bake: volume {scene.cycles.volume_bounces}, total {scene.cycles.max_bounces}; "
          f"{args.demo_width} px wide, {args.demo_samples} samples", flush=True)
    output = os.path.join(directory, "demo.png")

    def render():
        common.render(scene, output, args.demo_width, args.demo_samples)
        image = bpy.data.images.load(output, check_existing=False)
        pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
        image.pixels.foreach_get(pixels)
        bpy.data.images.remove(image)
        return float(pixels.reshape(-1, 4)[:, :3].mean())

    paired_rounds("demo", limits, args.rounds, render)


def main():
    args = parse_args()
    limits = [int(x) for x in args.bounces.split(",")]
    directory = tempfile.mkdtemp(prefix="firn_bounce_cost_")
    print(f"Blender {bpy.app.version_string}; volume and total bounces {limits}; {args.rounds} rounds", flush=True)
    for name in args.cases.split(",") if args.cases else []:
        suite_case(name, limits, args, directory)
    if not args.no_demo:
        demo(limits, args, directory)


main()
