"""Wall-clock timing shared by the tour and the benchmark (not by tests)."""
from __future__ import annotations

import time

import numpy as np


def median_time(fn, *, repeat: int = 5, warmup: int = 1, budget: float = 2.0) -> float:
    """Median wall time of ``fn()`` over ``repeat`` runs after ``warmup`` runs.

    Fewer runs are made when one run is long, so that the whole measurement
    stays within about ``budget`` seconds (at least one timed run)."""
    for _ in range(warmup):
        t0 = time.perf_counter()
        fn()
        first = time.perf_counter() - t0
    if warmup and first * repeat > budget:
        repeat = max(1, int(budget / max(first, 1e-9)))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def fmt_time(t: float) -> str:
    if t < 1e-3:
        return f"{t * 1e6:.1f} us"
    if t < 1:
        return f"{t * 1e3:.2f} ms"
    return f"{t:.2f} s"
