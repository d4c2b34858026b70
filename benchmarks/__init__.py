"""Benchmarks: ``python -m benchmarks --out benchmarks/results.md`` (``make bench``)."""

import time


def best_time(fn, repeat: int = 3) -> float:
    """Shortest wall time [s] of ``repeat`` calls of ``fn()``."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
