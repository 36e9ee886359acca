"""Timing shared by the benchmark scripts: the minimum over repeats of the mean time per call."""

from __future__ import annotations

import gc
from collections.abc import Callable
from itertools import repeat
from time import perf_counter


def _run(fn: Callable[[], object], n: int) -> float:
    start = perf_counter()
    for _ in repeat(None, n):
        fn()
    return perf_counter() - start


def best_us(fn: Callable[[], object], budget: float, repeats: int) -> float:
    """Minimum over ``repeats`` of the mean µs per call; ``n`` calls take ~``budget`` s."""
    n = 1
    while (elapsed := _run(fn, n)) < budget / 20:  # calibrate (and warm up)
        n *= 2
    n = max(1, round(n * budget / elapsed))
    gc.disable()
    try:
        return min(_run(fn, n) for _ in range(repeats)) / n * 1e6
    finally:
        gc.enable()


def best_ms(fn: Callable[[], object], repeats: int = 3) -> float:
    """Minimum over ``repeats`` of one call's wall time in ms, after one warm-up call (for calls of 10 ms and up)."""
    fn()
    return min(_run(fn, 1) for _ in range(repeats)) * 1e3
