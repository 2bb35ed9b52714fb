"""Timing shared by the benches."""

import time


def fastest(runs, work):
    """(fastest seconds, last result) of `runs` calls of work()."""
    best, result = float("inf"), None
    for _ in range(runs):
        began = time.perf_counter()
        result = work()
        best = min(best, time.perf_counter() - began)
    return best, result
