"""How promptly Esc stops a bake: the seconds from `Progress.cancel()` until `firncore.bake` raises
`firncore.Cancelled`, at instants spread over the bake (docs/bake.md, Cancelling).

    PYTHONPATH=build/python:bench /usr/bin/python3 bench/cancel_latency.py [--scenes car,spray_dense,ball_grey]
        [--instants 16] [--car build/car_inputs] [--stage NAME --delays 0.5,2]

Per scene, a first uncancelled bake (FINAL, seed 0, as bench/suite_grids.py bakes) gives the duration D and the
stages the progress showed (polled every 5 ms: when each began). Then `--instants` fresh bakes, each on a fresh copy
of the density, run on a worker thread (firncore releases the GIL, as the add-on's worker does); the main thread
cancels the i-th at (i + 0.5) / N of D. Printed per instant: when, the stage the progress showed at the cancel, and
the latency (s) until the call raised Cancelled, or until it returned unstopped ("(not stopped)": the cancel
came too late for any check, or in work that checks none; a latency too), then the scene's worst
latency and the machine's load average (the machine may be shared: latencies grow with its load). With --stage,
no uncancelled bake: one bake per delay, cancelled that many seconds after the progress first shows stage NAME
(a stage a shared machine's spread of durations makes the instants miss). The inputs: the
car's from bench/car_scene.py (bench/car_bake.py writes them where absent), the cases' from bench/bake_suite.py.
"""

import argparse
import os
import shutil
import tempfile
import threading
import time

import firncore


def scene_bakers(names, car_folder):
    """name -> bake(path, progress) and name -> write(path) of its density, for the scenes asked."""
    bakers = {}
    for name in names:
        if name == "car":
            import car_bake

            folder = car_bake.car_folder(car_folder)
            inputs = car_bake.car_inputs(folder)
            source = os.path.join(folder, "car_density.vdb")

            def bake(path, progress, inputs=inputs):
                optics, suns, sky, occluders = inputs
                firncore.bake(path, optics, suns=suns, sky=sky, occluders=occluders, quality="FINAL", seed=0,
                              progress=progress)

            bakers[name] = (bake, lambda path, source=source: shutil.copy(source, path))
        else:
            import bake_suite

            case = bake_suite.case(name)

            def bake(path, progress, case=case):
                firncore.bake(path, case.optics, suns=case.suns(), sky=case.skies(), occluders=case.occluders,
                              quality="FINAL", seed=0, sky_samples=0, progress=progress)

            bakers[name] = (bake, lambda path, case=case: bake_suite.write_density(path, case.density, case.voxel))
    return bakers


def timed_bake(bake, write, cancel_at=None, stage_shown=None):
    """One bake on a worker thread of a fresh density file. Returns (seconds from start to end, stages as
    [(seconds, name)] polled every 5 ms, the stage at the cancel, the seconds from the cancel to the call's end or
    None without a cancel, whether it raised Cancelled). With `stage_shown`, cancel_at counts from when the progress
    first shows that stage."""
    progress = firncore.Progress()
    outcome = {}
    with tempfile.TemporaryDirectory() as scratch:
        path = os.path.join(scratch, "snow.vdb")
        write(path)

        def work():
            try:
                bake(path, progress)
            except firncore.Cancelled:
                outcome["cancelled"] = True
            outcome["ended"] = time.perf_counter()

        worker = threading.Thread(target=work)
        start = time.perf_counter()
        worker.start()
        stages, cancelled_at, stage_at_cancel = [], None, None
        while worker.is_alive():
            now = time.perf_counter() - start
            stage = progress.stage
            if not stages or stages[-1][1] != stage:
                stages.append((now, stage))
            shown = next((at for at, name in stages if name == stage_shown), None) if stage_shown else 0.0
            if cancel_at is not None and cancelled_at is None and shown is not None and now >= shown + cancel_at:
                stage_at_cancel = stage
                cancelled_at = time.perf_counter()
                progress.cancel()
            worker.join(0.005)
        latency = outcome["ended"] - cancelled_at if cancelled_at is not None else None
        return outcome["ended"] - start, stages, stage_at_cancel, latency, outcome.get("cancelled", False)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", default="car,spray_dense,ball_grey")
    parser.add_argument("--instants", type=int, default=16)
    parser.add_argument("--car", default=None, help="the car's bake inputs (bench/car_bake.py's default folder)")
    parser.add_argument("--stage", default=None, help="cancel --delays seconds after this stage first shows")
    parser.add_argument("--delays", default="0.5,2")
    args = parser.parse_args()
    bakers = scene_bakers(args.scenes.split(","), args.car)
    print(f"firncore {firncore.__version__}, {firncore.hardware_threads()} threads, FINAL, seed 0; "
          f"{args.instants} cancels per scene", flush=True)
    worst = {}
    if args.stage:
        for name, (bake, write) in bakers.items():
            for delay in (float(d) for d in args.delays.split(",")):
                load = os.getloadavg()[0]
                _, _, stage, latency, stopped = timed_bake(bake, write, delay, args.stage)
                shown = "ended" if latency is None else f"{latency:.3f}" + ("" if stopped else " (not stopped)")
                print(f"{name}: {delay:.1f} s after {args.stage!r}: latency {shown} ({stage}); load average "
                      f"{load:.1f}", flush=True)
        return
    for name, (bake, write) in bakers.items():
        load = os.getloadavg()[0]
        duration, stages, _, _, _ = timed_bake(bake, write)
        print(f"\n{name}: uncancelled bake {duration:.2f} s (load average {load:.1f}); stages began at")
        for at, stage in stages:
            print(f"  {at:7.2f} s  {stage}")
        print(f"  {'cancel at s':>11}  {'latency s':>9}  stage at the cancel")
        latencies = []
        for i in range(args.instants):
            at = (i + 0.5) / args.instants * duration
            _, _, stage, latency, stopped = timed_bake(bake, write, cancel_at=at)
            if latency is None:  # the bake ended before the instant
                print(f"  {at:11.2f}  {'ended':>9}  (before the cancel)", flush=True)
                continue
            print(f"  {at:11.2f}  {latency:9.3f}  {stage}" + ("" if stopped else " (not stopped)"), flush=True)
            latencies.append((latency, stage))
        worst[name] = max(latencies) if latencies else (float("nan"), "")
        print(f"{name}: worst {worst[name][0]:.3f} s ({worst[name][1]}); load average now "
              f"{os.getloadavg()[0]:.1f}", flush=True)
    print("\nworst per scene: " + ", ".join(f"{n} {w[0]:.3f} s" for n, w in worst.items()))


if __name__ == "__main__":
    main()
