"""Where the car's FINAL bake spends its processor time against the slab's (issue 10 item 4; docs/benchmarks.md,
car-lattice): one bake in this process with the times its progress stages begin (CLOCK_MONOTONIC, perf's clock), perf's
samples split by those stages, and the sub-stage laps of bench/car_lattice_laps.diff tabled against the slab's per
active voxel and per surface voxel.

    PYTHONPATH=build/python perf record -F 499 -k CLOCK_MONOTONIC -o car.data \\
        /usr/bin/python3 bench/car_profile.py bake car car.json [FOLDER]      # or: bake slab slab.json
    /usr/bin/python3 bench/car_profile.py split car.data car.json [symbols per stage]
    # with bench/car_lattice_laps.diff applied (its laps go to stderr):
    PYTHONPATH=build/python /usr/bin/python3 bench/car_profile.py bake car car.json 2> car_laps.txt
    /usr/bin/python3 bench/car_profile.py laps car_laps.txt[,more] slab_laps.txt[,more]

The car's inputs as bench/car_scene.py writes them (default /tmp/car-rays/car); the slab bench/bake_scaling.py's
bumpy layer at 1 M voxels.
"""

import bisect
import collections
import json
import os
import re
import subprocess
import sys
import tempfile
import time

CAR_VOXELS, CAR_SURFACE = 2724345, 500313  # the car's active and surface voxels (car-rays' inputs)
SLAB_VOXELS, SLAB_SURFACE = 1053749, 117116


def bake(which, out, folder="/tmp/car-rays/car"):
    import bake_scaling
    import car_bake
    import firncore

    stages = []

    def report(fraction, stage):
        if not stages or stages[-1][1] != stage:
            stages.append((time.clock_gettime(time.CLOCK_MONOTONIC), stage))

    progress = firncore.Progress(report)
    with tempfile.TemporaryDirectory() as scratch:
        slab = os.path.join(scratch, "slab.vdb")
        if which == "slab":
            bake_scaling.bumpy_layer(slab, 1_000_000)
        stages.append((time.clock_gettime(time.CLOCK_MONOTONIC), "start"))
        cpu = time.process_time()
        stats = car_bake.bake_car(folder, 0, progress) if which == "car" else bake_scaling.bake_layer(slab, progress)
        stats["cpu_seconds_total"] = time.process_time() - cpu  # with the file's read and write
        stages.append((time.clock_gettime(time.CLOCK_MONOTONIC), "end"))
    with open(out, "w") as f:
        json.dump({"stages": stages, "stats": stats}, f, indent=1)
    print(json.dumps(stats))


def split(data, stages_file, top=25):
    """perf's samples by the stage they fell in (the n-th stage as n:name), the leading symbols of each."""
    stages = json.load(open(stages_file))["stages"]
    times = [t for t, _ in stages]
    script = subprocess.run(["perf", "script", "-i", data, "-F", "time,ip,sym", "--ns"], capture_output=True,
                            text=True).stdout
    by = collections.defaultdict(collections.Counter)
    for line in script.splitlines():
        parts = line.split(None, 2)
        if len(parts) < 3:
            continue
        try:
            t = float(parts[0].rstrip(":"))
        except ValueError:
            continue
        k = bisect.bisect_right(times, t) - 1
        symbol = parts[2]
        while re.search(r"<[^<>]*>", symbol):  # templates' arguments dropped, innermost first
            symbol = re.sub(r"<[^<>]*>", "", symbol)
        by[f"{k}:{stages[k][1]}" if k >= 0 else "before"][symbol[:120]] += 1
    for stage, counts in by.items():
        print(f"== {stage}: {sum(counts.values())} samples")
        for symbol, n in counts.most_common(top):
            print(f"  {n:6d}  {symbol}")


def laps(files):
    """The laps of bench/car_lattice_laps.diff summed by name over a bake (the gathering's gridValues apart from the
    grids'), averaged over the files."""
    runs = []
    for name in files.split(","):
        run, seen = collections.OrderedDict(), collections.Counter()
        for line in open(name):
            if line.startswith("LAP "):
                label, seconds = line[4:].rsplit(None, 1)
                label = label.strip()
                if label.startswith("gridValues"):
                    seen[label] += 1
                    label = ("gather " if seen[label] == 1 else "grids ") + label
                run[label] = run.get(label, 0.0) + float(seconds)
        runs.append(run)
    return list(runs[0]), {k: sum(r.get(k, 0.0) for r in runs) / len(runs) for k in runs[0]}


def table(car_files, slab_files):
    labels, car = laps(car_files)
    _, slab = laps(slab_files)
    print(f"{'lap (processor s)':40s} {'car':>6s} {'slab':>6s} {'slab x vox':>10s} {'slab x surf':>11s} {'excess':>7s}")
    sums = [0.0] * 4
    for label in labels:
        c, s = car.get(label, 0.0), slab.get(label, 0.0)
        if c < 0.02 and s < 0.02:
            continue
        per_voxel, per_surface = s * CAR_VOXELS / SLAB_VOXELS, s * CAR_SURFACE / SLAB_SURFACE
        sums = [a + b for a, b in zip(sums, (c, s, per_voxel, per_surface))]
        print(f"{label:40s} {c:6.2f} {s:6.2f} {per_voxel:10.2f} {per_surface:11.2f} {c - per_voxel:+7.2f}")
    print(f"{'all laps':40s} {sums[0]:6.2f} {sums[1]:6.2f} {sums[2]:10.2f} {sums[3]:11.2f} {sums[0] - sums[2]:+7.2f}")


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "bake":
        bake(*sys.argv[2:])
    elif mode == "split":
        split(sys.argv[2], sys.argv[3], *(int(a) for a in sys.argv[4:]))
    else:
        table(sys.argv[2], sys.argv[3])
