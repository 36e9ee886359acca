"""The sweep engine: where tasks run (here, a process pool, a dask cluster), in chunks, with a progress line.

A chunk of tasks travels to a worker in one round trip; :func:`run_chunk` runs it there and never raises
for a task (its error text is recorded instead); :func:`run_tasks` sends the chunks and hands each finished
one to a collector.
"""

from __future__ import annotations

import math
import os
import pickle
import time
import traceback
from collections.abc import Callable, Mapping
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from typing import Any, TextIO

from ..errors import InputError
from .sweep_result import SweepError, canonical_json

__all__ = ["Progress", "Task", "checked_executor", "run_chunk", "run_tasks"]

Task = Callable[[dict[str, Any]], Mapping[str, Any]]


def _error_text(exc: BaseException) -> str:
    where = traceback.extract_tb(exc.__traceback__)[-1:] if exc.__traceback__ else []
    at = f" (at {where[0].filename}:{where[0].lineno})" if where else ""
    return f"{type(exc).__name__}: {exc}{at}"


def run_chunk(task: Task, chunk: list[tuple[int, dict[str, Any]]]) -> list[tuple[int, str | None, str | None]]:
    """Run tasks in a worker: (index, result as JSON text, error text) for each; never raises for a task."""
    out: list[tuple[int, str | None, str | None]] = []
    for index, params in chunk:
        try:
            result = task(params)
            if not isinstance(result, Mapping):
                raise TypeError(f"a task must return a dict of numbers, got {type(result).__name__}")
            out.append((index, canonical_json(dict(result), "a task's result"), None))
        except Exception as exc:  # recorded, never dropped: one bad point must not stop a sweep
            out.append((index, None, _error_text(exc)))
    return out


class Progress:
    """``done/total · tasks/s · time left`` on stderr, at most a few times a second."""

    def __init__(self, total: int, stream: TextIO | None) -> None:
        self.total, self.stream, self.done, self.failed = total, stream, 0, 0
        self.start = self.last = time.perf_counter()
        self.tty = bool(stream is not None and getattr(stream, "isatty", lambda: False)())

    def update(self, n: int, failed: int) -> None:
        self.done += n
        self.failed += failed
        now = time.perf_counter()
        if self.stream is not None and (now - self.last > (0.25 if self.tty else 5.0) or self.done == self.total):
            self.last = now
            rate = self.done / max(now - self.start, 1e-9)
            left = (self.total - self.done) / rate if rate > 0 else math.inf
            bad = f" · {self.failed} failed" if self.failed else ""
            line = (
                f"sweep: {self.done}/{self.total} tasks ({100 * self.done / max(self.total, 1):.0f} %) · "
                f"{rate:.1f} tasks/s · ~{left:.0f} s left{bad}"
            )
            self.stream.write(("\r" + line) if self.tty else line + "\n")
            if self.tty and self.done == self.total:
                self.stream.write("\n")
            self.stream.flush()


def _workers(executor: Any) -> int:
    n = getattr(executor, "_max_workers", None)  # ProcessPoolExecutor, ThreadPoolExecutor
    return int(n) if isinstance(n, int) and n > 0 else os.cpu_count() or 1


def checked_executor(executor: Any, chunk: int | None, task: Task, name: str) -> Executor | str | None:
    """``executor`` checked (a dask Client becomes its executor), ``chunk`` checked, and ``task`` checked to
    be picklable when it goes to worker processes (``name``: the task's name, for the message)."""
    if chunk is not None and (isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1):
        raise InputError(f"chunk must be a positive integer, got {chunk!r}")
    if isinstance(executor, str) and executor != "serial":
        raise InputError(f"executor={executor!r} is unknown; use None, 'serial', an Executor or a dask Client")
    get_executor = getattr(executor, "get_executor", None)
    if callable(get_executor):  # a dask distributed.Client: its concurrent.futures interface
        executor = get_executor()
    if executor is not None and not isinstance(executor, (str, Executor)):
        raise InputError(
            f"executor must be None, 'serial', a concurrent.futures.Executor or a dask Client, "
            f"got {type(executor).__name__}"
        )
    if executor is None or isinstance(executor, ProcessPoolExecutor):
        try:
            pickle.dumps(task)
        except Exception as exc:
            raise SweepError(
                f"the task {name} cannot be sent to worker processes ({type(exc).__name__}: {exc}); "
                "define it as a top-level function of a module (not a lambda or a nested function), "
                "or use executor='serial'"
            ) from None
    return executor  # type: ignore[no-any-return]


def run_tasks(
    task: Task,
    plist: list[dict[str, Any]],
    todo: list[int],
    pool: Executor | str | None,
    chunk: int | None,
    collect: Callable[[list[tuple[int, str | None, str | None]]], None],
) -> None:
    """Run the tasks ``todo`` in chunks, here (``"serial"``) or on ``pool``, each chunk to ``collect``."""
    if not todo:
        return
    if pool == "serial":
        size = chunk or 1
        for k in range(0, len(todo), size):
            collect(run_chunk(task, [(i, plist[i]) for i in todo[k : k + size]]))
        return
    assert isinstance(pool, Executor)
    size = chunk or max(1, min(256, math.ceil(len(todo) / (4 * _workers(pool)))))
    futures: list[Future[Any]] = [
        pool.submit(run_chunk, task, [(i, plist[i]) for i in todo[k : k + size]]) for k in range(0, len(todo), size)
    ]
    try:
        for fut in as_completed(futures):
            collect(fut.result())
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise
