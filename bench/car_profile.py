"""Where the car's FINAL bake spends its processor time against the slab's (issue 10 item 4; docs/benchmarks.md,
car-lattice): one bake in this process with the times its progress stages begin (CLOCK_MONOTONIC, perf's clock), perf's
samples split by those stages, and the sub-stage laps of bench/car_lattice_laps.diff tabled against the slab's per
active voxel and per surface voxel.

    PYTHONPATH=build/python perf record -F 499 -k CLOCK_MONOTONIC -o car.data \\
        /usr/bin/python3 bench/car_profile.py bake car car.json [FOLDER]      # or: bake slab slab.json
    /usr/bin/python3 bench/car_profile.py split car.data car.json [symbols per stage]
    # both cores busy? a system-wide record of the scheduler's switches beside one bake:
    perf record -a -e sched:sched_switch -k CLOCK_MONOTONIC -o switches.data &   # stopped (kill -INT) after the bake
    PYTHONPATH=build/python perf record -F 499 -k CLOCK_MONOTONIC -o car.data \\
        /usr/bin/python3 bench/car_profile.py bake car car.json [FOLDER]
    /usr/bin/python3 bench/car_profile.py threads switches.data car.data car.json [symbols per stage]
    # with bench/car_lattice_laps.diff applied (its laps go to stderr):
    PYTHONPATH=build/python /usr/bin/python3 bench/car_profile.py bake car car.json 2> car_laps.txt
    /usr/bin/python3 bench/car_profile.py laps car_laps.txt[,more] slab_laps.txt[,more]

The car's inputs as bench/car_scene.py writes them (FOLDER, default build/car_inputs: bench/car_bake.py's car_folder,
which writes them there first where they are missing); the slab bench/bake_scaling.py's bumpy layer at 1 M voxels.
A record with call chains (`perf record -g`) splits as one without: each sample counts its leaf symbol (perf script
--hide-call-graph; without it every sample of such a record was dropped or misread, car-surface-b).
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


def bake(which, out, folder=None):
    import bake_scaling
    import car_bake
    import firncore

    if which == "car":
        folder = car_bake.car_folder(folder)

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
        # the process's threads, the calling one first (its id is the process's)
        threads = [os.getpid()] + sorted(int(t) for t in os.listdir("/proc/self/task") if int(t) != os.getpid())
        json.dump({"stages": stages, "stats": stats, "threads": threads}, f, indent=1)
    print(json.dumps(stats))


def plain(symbol):
    """A symbol without its templates' arguments (innermost first)."""
    while re.search(r"<[^<>]*>", symbol):
        symbol = re.sub(r"<[^<>]*>", "", symbol)
    return symbol


def split(data, stages_file, top=25):
    """perf's samples by the stage they fell in (the n-th stage as n:name), the leading symbols of each."""
    stages = json.load(open(stages_file))["stages"]
    times = [t for t, _ in stages]
    script = subprocess.run(["perf", "script", "-i", data, "-F", "time,ip,sym", "--ns", "--hide-call-graph"],
                            capture_output=True, text=True).stdout
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
        by[f"{k}:{stages[k][1]}" if k >= 0 else "before"][plain(parts[2])[:120]] += 1
    for stage, counts in by.items():
        print(f"== {stage}: {sum(counts.values())} samples")
        for symbol, n in counts.most_common(top):
            print(f"  {n:6d}  {symbol}")


def switches(data, threads):
    """Each thread's states in a system-wide sched_switch record: (time, "run" | "R" preempted | "S" asleep)."""
    script = subprocess.run(["perf", "script", "-i", data, "-F", "time,trace", "--ns"], capture_output=True,
                            text=True).stdout
    states = collections.defaultdict(list)
    for line in script.splitlines():
        m = re.match(r"\s*([\d.]+):\s+prev_comm=.* prev_pid=(\d+) .*prev_state=(\S+) ==> next_comm=.* next_pid=(\d+) ",
                     line)
        if m and int(m[2]) in threads:
            states[int(m[2])].append((float(m[1]), "R" if m[3].startswith("R") else "S"))
        if m and int(m[4]) in threads:
            states[int(m[4])].append((float(m[1]), "run"))
    return states


def threads(switch_data, sample_data, stages_file, top=8):
    """Are both cores busy in every stage? Per stage, each bake thread's seconds running, preempted (the machine's
    load) and asleep (waiting for work), from a system-wide sched_switch record beside the bake; and perf's samples of
    the calling thread taken while the TBB worker slept: the stage's serial processor time, with its leading symbols."""
    run = json.load(open(stages_file))
    stages, main = run["stages"], run["threads"][0]
    times = [t for t, _ in stages]
    states = switches(switch_data, set(run["threads"]))
    worker = max((tid for tid in states if tid != main), key=lambda tid: len(states[tid]))
    seconds = collections.defaultdict(collections.Counter)  # (stage, thread) -> state -> s
    for tid in (main, worker):
        events = sorted(states[tid])
        for (t0, state), (t1, _) in zip(events, events[1:]):
            t0, t1 = max(t0, times[0]), min(t1, times[-1])
            while t0 < t1:  # split at the stages' starts
                k = bisect.bisect_right(times, t0) - 1
                end = min(t1, times[k + 1])
                seconds[k, tid][state] += end - t0
                t0 = end
    asleep_from = sorted(states[worker])
    starts = [t for t, _ in asleep_from]

    def worker_asleep(t):
        i = bisect.bisect_right(starts, t) - 1
        return i >= 0 and asleep_from[i][1] == "S"

    script = subprocess.run(["perf", "script", "-i", sample_data, "-F", "tid,time,ip,sym", "--ns",
                             "--hide-call-graph"], capture_output=True, text=True).stdout
    alone, together = collections.defaultdict(collections.Counter), collections.Counter()
    for line in script.splitlines():
        m = re.match(r"\s*(\d+)\s+([\d.]+):\s+[0-9a-f]+\s+(.*)$", line)
        if not m or int(m[1]) != main:
            continue
        t = float(m[2])
        k = bisect.bisect_right(times, t) - 1
        if not 0 <= k < len(stages) - 1:
            continue
        if worker_asleep(t):
            alone[k][plain(m[3].strip())[:100]] += 1
        else:
            together[k] += 1
    print(f"calling thread {main}, TBB worker {worker}; s on the clock, samples of the calling thread")
    print(f"{'stage':32s} {'main run':>8s} {'preempt':>7s} {'asleep':>6s} {'worker run':>10s} {'preempt':>7s} "
          f"{'asleep':>6s}  {'main alone':>10s} {'with':>5s}  serial share")
    for k in range(len(stages) - 1):
        m, w = seconds[k, main], seconds[k, worker]
        n_alone = sum(alone[k].values())
        share = n_alone / max(n_alone + together[k], 1)
        print(f"{stages[k][1][:32]:32s} {m['run']:8.2f} {m['R']:7.2f} {m['S']:6.2f} {w['run']:10.2f} {w['R']:7.2f} "
              f"{w['S']:6.2f}  {n_alone:10d} {together[k]:5d}  {share:6.1%}")
    for k in range(len(stages) - 1):
        if alone[k]:
            print(f"== {k}:{stages[k][1]}: the calling thread alone, leading symbols")
            for symbol, n in alone[k].most_common(top):
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
    mode = sys.argv[1] if len(sys.argv) > 1 else "--help"
    if mode in ("-h", "--help"):
        print(__doc__)
    elif mode == "bake":
        bake(*sys.argv[2:])
    elif mode == "threads":
        threads(sys.argv[2], sys.argv[3], sys.argv[4], *(int(a) for a in sys.argv[5:]))
    elif mode == "split":
        split(sys.argv[2], sys.argv[3], *(int(a) for a in sys.argv[4:]))
    else:
        table(sys.argv[2], sys.argv[3])
