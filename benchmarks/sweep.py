"""Throughput of `gausspp.sweep`: tasks/s on 1 and 2 local workers, parallel efficiency, per-task overhead.

The task is `simulate_task` on the pendulum (RK4 with the direct step, 200 steps: ≈10 ms), a Monte Carlo
over the initial velocity (one model, built once per worker). Each pool is started and warmed up (worker
start, imports, the model built once per worker) before the clock starts; that warm-up is printed as its
own figure. The task's own time in this process and the serial, 1- and 2-worker sweeps are timed in
alternation, several times each (the machine is shared and noisy): the best and the median are printed,
and the efficiency is taken repeat by repeat. Next to each repeat, the machine's own scaling is measured
without the sweep — two pure-Python loops at once against one: on a shared virtual machine two busy
vCPUs can each run much slower than one, with no sign of it in the process's CPU time — and the sweep's
efficiency is also given relative to it. The sweep's own cost per task is measured apart, with a task
that does nothing.

    .venv/bin/python benchmarks/sweep.py [--tasks N] [--repeats R] [--chunk C]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from concurrent.futures import Executor, ProcessPoolExecutor
from typing import Any

import numpy as np

from gausspp.studies.sweeps import grid, simulate_task, sweep


def noop_task(params: dict[str, Any]) -> dict[str, float]:
    """No work: what is left is the sweep's own cost (pickling, round trips, JSON, bookkeeping)."""
    return {"y": float(params["v_scale"])}


def params(n: int) -> list[dict[str, float]]:
    rng = np.random.default_rng(0)
    v_scale = [float(x) for x in rng.uniform(0.5, 1.5, n)]
    return grid(omega0=[1.0], phi0=[0.3], t_end=[0.2], dt=[1e-3], method=["rk4"], v_scale=v_scale)


def own_times(ps: list[dict[str, float]], repeats: int) -> list[float]:
    """Seconds per task run directly in this process (model already cached), one figure per repeat."""
    simulate_task(ps[0])
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        for p in ps:
            simulate_task(p)
        out.append((time.perf_counter() - start) / len(ps))
    return out


def spin(n: int) -> float:
    """A pure-Python CPU-bound loop: the machine's own speed, without the sweep."""
    x = 0
    for i in range(n):
        x += i * i
    return float(x)


def machine_scaling(pools: dict[int, ProcessPoolExecutor], n: int = 2_000_000) -> float:
    """Time of one loop alone / time of two at once on two workers: 1.0 if the two cores are really free."""
    start = time.perf_counter()
    pools[1].submit(spin, n).result()
    one = time.perf_counter() - start
    start = time.perf_counter()
    for fut in [pools[2].submit(spin, n) for _ in range(2)]:
        fut.result()
    return one / (time.perf_counter() - start)


def rate(task: Any, ps: list[dict[str, float]], executor: Executor | str, chunk: int | None) -> float:
    res = sweep(task, ps, executor=executor, chunk=chunk, progress=False)
    assert res.ok, res.errors
    return res.tasks_per_second


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--chunk", type=int, default=None, help="tasks per round trip (default: the sweep's choice)")
    args = ap.parse_args()
    ps = params(args.tasks)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"task: simulate_task, pendulum, RK4 direct, 200 steps; {args.tasks} tasks per sweep; {args.repeats} repeats; "
        f"chunk {args.chunk or 'default'}; {os.cpu_count()} CPUs; load average at start {load:.2f}"
    )

    pools: dict[int, ProcessPoolExecutor] = {}
    warmup: dict[int, float] = {}
    try:
        for workers in (1, 2):
            start = time.perf_counter()
            pools[workers] = ProcessPoolExecutor(workers)
            rate(simulate_task, ps[: 8 * workers], pools[workers], 1)  # every worker: started, imports, model
            warmup[workers] = time.perf_counter() - start

        noop: dict[str, list[float]] = {"serial": [], "1 worker": [], "2 workers": []}
        rates: dict[int | str, list[float]] = {"serial": [], 1: [], 2: []}
        own: list[float] = []
        ceiling: list[float] = []
        for _ in range(args.repeats):  # alternated, so that a burst of load on the machine hits every setting
            own += own_times(ps[:100], 1)
            noop["serial"].append(rate(noop_task, ps, "serial", args.chunk))
            noop["1 worker"].append(rate(noop_task, ps, pools[1], args.chunk))
            noop["2 workers"].append(rate(noop_task, ps, pools[2], args.chunk))
            ceiling.append(machine_scaling(pools))
            for key in ("serial", 1, 2):
                rates[key].append(rate(simulate_task, ps, "serial" if key == "serial" else pools[int(key)], args.chunk))
    finally:
        for pool in pools.values():
            pool.shutdown()

    t_task = statistics.median(own)
    print(f"task's own time (in-process, no sweep):  best {1e3 * min(own):6.2f} ms, median {1e3 * t_task:6.2f} ms")
    print("sweep's own cost per task (a task that does nothing; median):")
    for name, r in noop.items():
        workers = 2 if name.startswith("2") else 1
        cost = workers / statistics.median(r)
        print(f"  {name:10s} {1e6 * cost:8.1f} µs of worker time per task = {100 * cost / t_task:5.2f} % of the task")
    print(
        f"{'':24s} {'warm-up':>8s} {'best':>9s} {'median':>9s}   wall per task × workers − own time "
        "(median; noisy: other moments)"
    )
    for key, label in (("serial", "serial executor"), (1, "process pool, 1 worker"), (2, "process pool, 2 workers")):
        r = rates[key]
        workers = 2 if key == 2 else 1
        overhead = statistics.median([workers / x - t for x, t in zip(r, own, strict=True)])
        warm = f"{warmup[key]:7.2f}s" if isinstance(key, int) else f"{'—':>8s}"
        print(
            f"{label:24s} {warm} {max(r):7.1f}/s {statistics.median(r):7.1f}/s   {1e6 * overhead:7.0f} µs "
            f"= {100 * overhead / t_task:5.1f} % of the task"
        )
    eff = [b / (2 * a) for a, b in zip(rates[1], rates[2], strict=True)]  # per repeat: same moment on the machine
    print(
        f"parallel efficiency, 2 workers vs 1: best {100 * max(eff):5.1f} %, "
        f"median {100 * statistics.median(eff):5.1f} %, worst {100 * min(eff):5.1f} %  (goal ≥ 80 %)"
    )
    print(
        f"the machine's own scaling, two CPU-bound loops at once vs one (same moments): best "
        f"{100 * max(ceiling):5.1f} %, median {100 * statistics.median(ceiling):5.1f} %"
    )
    relative = [e / c for e, c in zip(eff, ceiling, strict=True)]
    print(
        f"sweep efficiency / the machine's scaling, repeat by repeat: best {100 * max(relative):5.1f} %, "
        f"median {100 * statistics.median(relative):5.1f} %"
    )
    ideal = [r * t / 2 for r, t in zip(rates[2], own, strict=True)]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"2 workers against 2 ideal cores running the task's own time: best {100 * max(ideal):5.1f} %, "
        f"median {100 * statistics.median(ideal):5.1f} %; load average at the end {load:.2f}"
    )


if __name__ == "__main__":
    main()
