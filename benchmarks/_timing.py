"""Timing helper shared by the benchmark scripts (run as `python benchmarks/<script>.py`, so
this directory is on sys.path)."""

import time


def best_of(fn, repeat=3, warm_up=True):
    """(shortest wall time of `repeat` calls of fn in s, the last call's result); with
    warm_up one untimed call first (compilation, caches)."""
    if warm_up:
        fn()
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out
