"""Throughput of `gausspp.sweep`: tasks/s on 1 and 2 local workers, parallel efficiency, per-task overhead.

The task is `simulate_task` on the pendulum (RK4 with the direct step, 200 steps: ≈10 ms), a
Monte Carlo over the initial velocity (one model, built once per worker). Pools are started and warmed up (imports, the
model built once per worker) before the clock starts; the cold figure, with that start-up, is printed too.

    .venv/bin/python benchmarks/sweep.py [--tasks N]
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from gausspp.sweep import grid, simulate_task, sweep


def params(n: int) -> list[dict[str, float]]:
    rng = np.random.default_rng(0)
    return grid(omega0=[1.0], phi0=[0.3], t_end=[0.2], v_scale=[float(x) for x in rng.uniform(0.5, 1.5, n)])


def own_time(ps: list[dict[str, float]]) -> float:
    """Seconds per task run directly in this process (model already cached)."""
    simulate_task(ps[0])
    best = np.inf
    for _ in range(3):  # the minimum of repeats: the task's cost without the machine's noise
        start = time.perf_counter()
        for p in ps:
            simulate_task(p)
        best = min(best, (time.perf_counter() - start) / len(ps))
    return float(best)


def pooled(ps: list[dict[str, float]], workers: int) -> tuple[float, float]:
    """(warm tasks/s, cold tasks/s including pool start-up and the first model builds)."""
    start = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        cold = sweep(simulate_task, ps, executor=pool, progress=False)
        cold_rate = len(ps) / (time.perf_counter() - start)
        warm = sweep(simulate_task, ps, executor=pool, progress=False)
    assert cold.ok and warm.ok
    return warm.tasks_per_second, cold_rate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", type=int, default=300)
    args = ap.parse_args()
    ps = params(args.tasks)
    t_task = own_time(ps[:50])
    print(f"task: simulate_task, pendulum, RK4 direct, 200 steps; {args.tasks} tasks; {os.cpu_count()} CPUs")
    print(f"task's own time (in-process, no sweep):   {1e3 * t_task:7.2f} ms  ({1 / t_task:7.1f} tasks/s)")
    serial = sweep(simulate_task, ps, executor="serial", progress=False)
    print(f"serial executor:                         {serial.tasks_per_second:7.1f} tasks/s")
    rates = {}
    for workers in (1, 2):
        warm, cold = pooled(ps, workers)
        rates[workers] = warm
        overhead = workers / warm - t_task
        print(
            f"process pool, {workers} worker{'s' if workers > 1 else ' '}:                 {warm:7.1f} tasks/s "
            f"(cold start: {cold:6.1f}); overhead per task {1e6 * overhead:6.0f} µs = "
            f"{100 * overhead / t_task:4.1f} % of the task"
        )
    efficiency = rates[2] / (2 * rates[1])
    print(f"parallel efficiency, 2 workers vs 1:     {100 * efficiency:5.1f} %  (goal ≥ 80 %)")
    print(
        f"  against the task's own time:           {100 * rates[2] * t_task / 2:5.1f} %  (2 workers vs 2 ideal cores)"
    )


if __name__ == "__main__":
    main()
