"""What a bake costs, measured in a fresh process (bench/bake_scaling.py, bench/car_bake.py): wall and processor
seconds (all threads: on a machine shared with other work, wall time is longer than processor time / threads) and
the peak resident memory the bake added to the process (getrusage's high-water mark over what the process held
just before it)."""

import multiprocessing
import os
import resource
import time


def resident_bytes():
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def measure(bake, *args):
    """Runs bake(*args) -> stats here; returns stats with `wall_seconds`, `cpu_seconds_total`, `peak_bytes`."""
    before = resident_bytes()
    started, cpu_started = time.perf_counter(), time.process_time()
    stats = bake(*args)
    stats["wall_seconds"] = time.perf_counter() - started
    stats["cpu_seconds_total"] = time.process_time() - cpu_started
    stats["peak_bytes"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 - before
    return stats


def measure_fresh(bake, *args):
    """measure() in a new process (spawned: a fresh interpreter, nothing held from earlier bakes)."""
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        return pool.apply(measure, (bake,) + args)
