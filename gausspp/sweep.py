"""Parameter sweeps on one core, all local cores or a dask cluster — without rewriting the task.

A sweep maps a *task* — a picklable top-level function taking one parameter dict and returning a
small dict of numbers — over a list of parameter dicts, on any :class:`concurrent.futures.Executor`:

>>> from gausspp.sweep import grid, realizability_task, sweep
>>> res = sweep(realizability_task, grid(lon=[0.0, 90.0], lat=[0.0, 45.0]), executor="serial", progress=False)
>>> res.column("margin").shape
(4,)

Where it runs (``executor=``):

- ``None`` (default): a local :class:`~concurrent.futures.ProcessPoolExecutor` with ``os.cpu_count()`` workers;
- ``"serial"``: in this process, one task after the other (debugging, tiny sweeps);
- any :class:`~concurrent.futures.Executor`, e.g. ``ProcessPoolExecutor(4)``;
- a dask cluster: ``distributed.Client("tcp://scheduler:8786").get_executor()`` (or the ``Client`` itself,
  whose executor interface is used). ``pip install gausspp[dask]``.

Tasks travel in chunks (one round trip per chunk amortizes the per-task overhead). Models are not free to
build (casadi compiles functions), so a task gets its model from :func:`cached_scene`, built once per
worker process and reused by every later task there.

Nothing is lost: with ``out=path`` every finished task is appended to a JSON-lines file as it arrives
(its index, its parameters, and its result or its error text). Running the same sweep with the same
``out`` again skips the tasks already recorded, so an interrupted sweep resumes where it stopped and the
merged result equals an uninterrupted run. A task that raises is recorded with its error; the others go on.
"""

from __future__ import annotations

import functools
import itertools
import json
import math
import os
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from .errors import GaussppError, InputError

__all__ = [
    "SweepError",
    "SweepResult",
    "cached_scene",
    "grid",
    "realizability_task",
    "simulate_task",
    "sweep",
]

Task = Callable[[dict[str, Any]], Mapping[str, Any]]


class SweepError(GaussppError):
    """A sweep cannot run as asked (e.g. its ``out`` file holds another sweep)."""


# -- parameters ---------------------------------------------------------------------------------------
def grid(**axes: Iterable[Any]) -> list[dict[str, Any]]:
    """The Cartesian product of the axes, as a list of parameter dicts (the first axis varies slowest).

    >>> grid(a=[1, 2], b=["x", "y"])
    [{'a': 1, 'b': 'x'}, {'a': 1, 'b': 'y'}, {'a': 2, 'b': 'x'}, {'a': 2, 'b': 'y'}]
    """
    names = list(axes)
    values = [list(v) for v in axes.values()]
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*values)]


def _canonical(obj: Any, what: str) -> str:
    """The JSON text of ``obj`` with sorted keys: how parameters and results are stored and compared."""
    try:
        return json.dumps(obj, sort_keys=True, default=_plain)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{what} must be JSON-serializable (numbers, strings, lists, dicts): {exc}") from None


def _plain(obj: Any) -> Any:
    """numpy scalars and arrays as Python numbers and lists (json's ``default`` hook)."""
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"{type(obj).__name__} {obj!r} is not JSON-serializable")


# -- the result ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SweepResult:
    """A finished sweep, in task order.

    Attributes
    ----------
    params : list of dict
        The parameters of every task.
    results : list of (dict or None)
        Each task's result (after a JSON round trip, so a resumed sweep equals an uninterrupted one),
        ``None`` where the task failed.
    errors : dict int → str
        Task index → the error text (exception type, message and the last traceback line) of failed tasks.
    wall_time : float
        Seconds for this call (tasks taken from ``out`` cost nothing).
    computed : int
        Tasks computed by this call; the others were read back from ``out``.
    """

    params: list[dict[str, Any]]
    results: list[dict[str, Any] | None]
    errors: dict[int, str]
    wall_time: float
    computed: int

    @property
    def tasks_per_second(self) -> float:
        """Throughput of this call: tasks computed per second of wall time."""
        return self.computed / self.wall_time if self.wall_time > 0 else math.inf

    @property
    def ok(self) -> bool:
        """True if no task failed."""
        return not self.errors

    def column(self, key: str) -> np.ndarray:
        """``result[key]`` of every task as a float array, NaN where the task failed or lacks ``key``."""
        return np.array([np.nan if r is None else r.get(key, np.nan) for r in self.results], dtype=float)

    def __len__(self) -> int:
        return len(self.params)


# -- per-worker model cache ---------------------------------------------------------------------------
def _freeze(value: Any) -> Any:
    if isinstance(value, Mapping):
        return tuple(sorted((k, _freeze(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple, np.ndarray)):
        return tuple(_freeze(v) for v in value)
    return value


def _thaw(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


@functools.lru_cache(maxsize=32)
def _scene(name: str, frozen: tuple[tuple[str, Any], ...]) -> Any:
    from . import scenes

    return scenes.get(name, **{k: _thaw(v) for k, v in frozen})


def cached_scene(name: str, **params: Any) -> Any:
    """``gausspp.scenes.get(name, **params)``, built once per process and reused (an LRU cache of 32).

    Task functions call this instead of building the model themselves: a worker then compiles each
    distinct model once, however many tasks it runs. Parameter lists are frozen into tuples for the cache.
    """
    return _scene(name, _freeze(params))


# -- built-in tasks -----------------------------------------------------------------------------------
def realizability_task(params: Mapping[str, Any]) -> dict[str, float]:
    """The servo-torque realizability margin for one body axis ``n`` (see :func:`gausspp.plot.servo_margin`).

    Parameters (keys of ``params``): ``lon``, ``lat`` — the direction of ``n`` in degrees;
    ``inertia`` (default ``(1, 2, 3)``) and ``l`` (default ``(1, 1, 1)``).
    Returns ``{"margin": ...}``.
    """
    from .plot import servo_margin

    lon, lat = math.radians(float(params["lon"])), math.radians(float(params["lat"]))
    n = (math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat))
    margin = servo_margin(params.get("inertia", (1.0, 2.0, 3.0)), params.get("l", (1.0, 1.0, 1.0)), n)
    return {"margin": float(margin)}


_SIMULATE_KEYS = ("scene", "t_end", "dt", "method", "solver", "v_scale")


def simulate_task(params: Mapping[str, Any]) -> dict[str, float]:
    """Simulate a scene briefly and reduce the run to a few numbers.

    Parameters (keys of ``params``): ``scene`` (default ``"pendulum"``), ``t_end`` (default 0.05),
    ``dt`` (default 1e-3), ``method`` (default ``"rk4"``), ``solver`` (default ``"direct"``),
    ``v_scale`` (default 1: the initial velocity is scaled by it — a Monte Carlo knob that keeps the
    data on velocity-level constraints); every other key is a scene parameter. The model comes from
    :func:`cached_scene`, so it is built once per worker.

    Returns ``{"residual", "energy_balance", "q_end_norm", "steps"}`` and ``"q_error"`` (the error of
    the final ``q`` against the scene's exact motion) where one is known.
    """
    from .simulate import simulate

    scene_params = {k: v for k, v in params.items() if k not in _SIMULATE_KEYS}
    scene = cached_scene(str(params.get("scene", "pendulum")), **scene_params)
    t_end = float(params.get("t_end", 0.05))
    traj = simulate(
        scene.model,
        scene.q0,
        float(params.get("v_scale", 1.0)) * np.asarray(scene.v0),
        t_end,
        dt=float(params.get("dt", 1e-3)),
        method=str(params.get("method", "rk4")),
        solver=str(params.get("solver", "direct")),
        lam0=scene.lam0,
    )
    out = {
        "residual": float(traj.max_residual()),
        "energy_balance": float(np.max(np.abs(traj.energy_balance()))),
        "q_end_norm": float(np.linalg.norm(traj.q[-1])),
        "steps": float(traj.steps),
    }
    if scene.exact is not None and params.get("v_scale", 1.0) == 1.0:
        out["q_error"] = float(np.max(np.abs(traj.q[-1] - scene.exact(float(traj.t[-1]))[0])))
    return out


# -- running ------------------------------------------------------------------------------------------
def _error_text(exc: BaseException) -> str:
    where = traceback.extract_tb(exc.__traceback__)[-1:] if exc.__traceback__ else []
    at = f" (at {where[0].filename}:{where[0].lineno})" if where else ""
    return f"{type(exc).__name__}: {exc}{at}"


def _run_chunk(task: Task, chunk: list[tuple[int, dict[str, Any]]]) -> list[tuple[int, str | None, str | None]]:
    """Run tasks in a worker: (index, result as JSON text, error text) for each; never raises for a task."""
    out: list[tuple[int, str | None, str | None]] = []
    for index, params in chunk:
        try:
            result = task(params)
            if not isinstance(result, Mapping):
                raise TypeError(f"a task must return a dict of numbers, got {type(result).__name__}")
            out.append((index, _canonical(dict(result), "a task's result"), None))
        except Exception as exc:  # recorded, never dropped: one bad point must not stop a sweep
            out.append((index, None, _error_text(exc)))
    return out


def _read_out(path: Path, keys: list[str]) -> dict[int, tuple[dict[str, Any] | None, str | None]]:
    """Records already in ``path`` (a truncated last line, left by a kill, is ignored)."""
    done: dict[int, tuple[dict[str, Any] | None, str | None]] = {}
    if not path.exists():
        return done
    with path.open(encoding="utf-8") as fh:
        for lineno, line in enumerate(fh, 1):
            try:
                rec = json.loads(line)
                index = int(rec["index"])
            except (ValueError, KeyError, TypeError):
                continue  # a partial line written when the process was killed
            if not 0 <= index < len(keys) or _canonical(rec.get("params"), "params") != keys[index]:
                raise SweepError(
                    f"out={str(path)!r} line {lineno} records task {index} with other parameters than this sweep "
                    f"({rec.get('params')!r}); it holds another sweep: use another out file or delete it"
                )
            done[index] = (rec.get("result"), rec.get("error"))
    return done


class _Progress:
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


def sweep(
    task: Task,
    params: Sequence[Mapping[str, Any]],
    *,
    executor: Executor | str | Any | None = None,
    chunk: int | None = None,
    out: str | os.PathLike[str] | None = None,
    progress: bool = True,
    retry_failed: bool = False,
) -> SweepResult:
    """Run ``task(p)`` for every ``p`` in ``params`` and collect the results in task order.

    Parameters
    ----------
    task : callable ``dict -> dict of numbers``
        A top-level (picklable) function. It should get its model from :func:`cached_scene`.
    params : list of dict
        JSON-serializable parameter dicts: :func:`grid` for a Cartesian product, or any list of samples.
    executor : None, "serial", a concurrent.futures.Executor, or a dask ``distributed.Client``
        Where the tasks run (see the module docstring). An executor passed in is left running.
    chunk : int, optional
        Tasks sent to a worker at once (default: about four chunks per worker, at most 256 tasks each).
    out : path, optional
        JSON-lines file: each finished task is appended as it arrives; tasks recorded there already are
        not run again (resume).
    progress : bool
        Tasks done/total, tasks/s and the estimated time left on stderr.
    retry_failed : bool
        On resume, run again the tasks recorded as failed (default: keep their recorded error).

    Returns
    -------
    SweepResult
    """
    start = time.perf_counter()
    plist = [dict(p) for p in params]
    keys = [_canonical(p, f"params[{i}]") for i, p in enumerate(plist)]
    if chunk is not None and (not isinstance(chunk, int) or chunk < 1):
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

    results: list[dict[str, Any] | None] = [None] * len(plist)
    errors: dict[int, str] = {}
    path = Path(out) if out is not None else None
    recorded = _read_out(path, keys) if path is not None else {}
    for index, (result, error) in recorded.items():
        if error is not None and retry_failed:
            continue
        results[index] = result
        if error is not None:
            errors[index] = error
    todo = [i for i in range(len(plist)) if i not in recorded or (retry_failed and recorded[i][1] is not None)]

    sink: TextIO | None = None
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        sink = path.open("a", encoding="utf-8")
        if sink.tell() > 0:  # a partial last line from a kill must not swallow the next record
            with path.open("rb") as fh:
                fh.seek(-1, os.SEEK_END)
                if fh.read(1) != b"\n":
                    sink.write("\n")
    bar = _Progress(len(todo), sys.stderr if progress else None)

    def collect(batch: list[tuple[int, str | None, str | None]]) -> None:
        for index, result_json, error in batch:
            result = json.loads(result_json) if result_json is not None else None
            results[index] = result
            if error is not None:
                errors[index] = error
            else:
                errors.pop(index, None)
            if sink is not None:
                record = {"index": index, "params": plist[index]}
                record.update({"error": error} if error is not None else {"result": result})
                sink.write(_canonical(record, "record") + "\n")
        if sink is not None:
            sink.flush()  # in the OS's hands: survives a kill of this process
        bar.update(len(batch), sum(e is not None for _, _, e in batch))

    owned = executor is None and len(todo) > 0
    pool: Executor | str | None = ProcessPoolExecutor(max_workers=os.cpu_count()) if owned else executor
    try:
        if not todo:
            pass
        elif pool == "serial":
            size = chunk or 1
            for k in range(0, len(todo), size):
                collect(_run_chunk(task, [(i, plist[i]) for i in todo[k : k + size]]))
        else:
            assert isinstance(pool, Executor)
            size = chunk or max(1, min(256, math.ceil(len(todo) / (4 * _workers(pool)))))
            futures: list[Future[Any]] = [
                pool.submit(_run_chunk, task, [(i, plist[i]) for i in todo[k : k + size]])
                for k in range(0, len(todo), size)
            ]
            try:
                for fut in as_completed(futures):
                    collect(fut.result())
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
    finally:
        if owned and isinstance(pool, Executor):
            pool.shutdown(wait=True, cancel_futures=True)
        if sink is not None:
            sink.close()
    return SweepResult(
        params=plist,
        results=results,
        errors=dict(sorted(errors.items())),
        wall_time=time.perf_counter() - start,
        computed=len(todo),
    )
