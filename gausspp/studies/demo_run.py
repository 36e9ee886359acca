"""The demo's rows as independent tasks on worker processes, handed back in the tables' order.

Each row of :mod:`gausspp.studies.demo` (a pair of one-step rows, a scene, a general-QP scene) and
the figures are one :class:`Task`. :func:`run` runs them on ``workers`` processes, the longest first,
reports each as it finishes (any order) and yields the results in the order of the plan, so that the
tables print as soon as their rows are ready.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import scenes
from . import demo


@dataclass(frozen=True)
class Task:
    """One row (or the figures): its table, its name, the call that computes it, whether it is a long one."""

    table: str
    name: str
    call: Callable[..., Any]
    args: tuple[Any, ...]
    heavy: bool = False


def plan(which: demo.Backends, out: Path) -> list[Task]:
    """The demo's tasks in the tables' order: the one-step pairs, every scene, the general-QP scenes, the figures."""
    steps = [
        Task("step", " ".join([name, *(f"{k}={v}" for k, v in (params or {}).items())]), demo.step_pair, (i,))
        for i, (name, params) in enumerate(demo.STEP_CASES)
    ]
    equality = [Task("scene", name, demo.scene_row, (name,)) for name in scenes.names("equality")]
    general = [
        Task("general", f"{name} ({backend})", demo.general_run, (name, backend), heavy=name in demo.GENERAL_T_END)
        for name in scenes.names("general")
        for backend in (which.first, which.second)
        if backend
    ]
    figures = [Task("figures", name, demo.figure, (out, name), heavy=True) for name in demo.FIGURES]
    return [*steps, *equality, *general, *figures]


def general_rows(which: demo.Backends, runs: Iterator[Any]) -> Iterator[demo.GeneralRow]:
    """The general-QP table's rows from the runs of :func:`plan`'s general tasks, taken in their order."""
    for name in scenes.names("general"):
        first = next(runs)
        yield demo.general_row(name, first, next(runs) if which.second else None)


def timed(call: Callable[..., Any], args: tuple[Any, ...]) -> tuple[Any, float]:
    """``call(*args)`` and its wall time in s."""
    start = time.perf_counter()
    value = call(*args)
    return value, time.perf_counter() - start


def workers() -> int:
    """Worker processes for the demo: two when the machine has two cores or more, else none (serial)."""
    return min(2, os.cpu_count() or 1)


def run(tasks: Sequence[Task], n_workers: int, done: Callable[[Task, float], None]) -> Iterator[Any]:
    """Each task's result, in the order of ``tasks``; ``done(task, seconds)`` as each finishes.

    With ``n_workers ≤ 1`` the tasks run here, one after the other. Otherwise on a process pool, the
    ``heavy`` ones submitted first; a task that raises raises here when its turn in the order comes.
    """
    if n_workers <= 1:
        for task in tasks:
            value, seconds = timed(task.call, task.args)
            done(task, seconds)
            yield value
        return
    pool = ProcessPoolExecutor(n_workers)
    try:
        order = sorted(range(len(tasks)), key=lambda i: not tasks[i].heavy)
        futures = {pool.submit(timed, tasks[i].call, tasks[i].args): i for i in order}
        ready: dict[int, Future[tuple[Any, float]]] = {}
        turn = 0
        for future in as_completed(futures):
            index = futures[future]
            if future.exception() is None:
                done(tasks[index], future.result()[1])
            ready[index] = future
            while turn in ready:
                yield ready.pop(turn).result()[0]
                turn += 1
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
