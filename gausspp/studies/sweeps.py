"""Parameter sweeps on one core, all local cores or a dask cluster — without rewriting the task.

``gausspp.sweep(fn_or_scene, grid | samples, *, executor=None, chunk=None, out=None)`` maps a *task* — a
picklable top-level function taking one parameter dict and returning a small dict of numbers — over a
list of parameter dicts, on any :class:`concurrent.futures.Executor`:

>>> from gausspp.sweeps import grid, realizability_task, sweep
>>> res = sweep(realizability_task, grid(lon=[0.0, 90.0], lat=[0.0, 45.0]), executor="serial", progress=False)
>>> res.column("margin").shape
(4,)

A scene name instead of a function runs the default per-scene task, :func:`simulate_task` (build the scene
with the parameters, simulate, reduce the run to a few numbers):

>>> res = sweep("pendulum", grid(omega0=[0.0, 1.0], t_end=[0.01]), executor="serial", progress=False)
>>> sorted(res.results[0])[:4]
['energy_balance', 'max_reaction', 'min_margin', 'q_end']

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
merged result equals an uninterrupted run. The log's first line names the task, so a log of another task,
or of other parameters, is refused rather than merged. A record a kill cut short (an unterminated last line)
is dropped silently; any other line that is not a record (damaged by hand or by a disk) is skipped with a
:class:`~gausspp.SweepLogWarning` naming the file and line number, and its task runs again — one bad line
does not cost the good results around it. A task that raises is recorded with its error; the
others go on. With ``out="name.npz"`` the JSON-lines log is ``name.jsonl`` beside it and the finished sweep is also
written as NPZ columns (:meth:`SweepResult.to_npz`; Parquet is not offered: it would need pyarrow).

:func:`work_precision` runs the report's error-against-run-time study (:mod:`gausspp.studies.work_precision`)
as a sweep (``gausspp sweep work-precision``).
"""

from __future__ import annotations

import functools
import itertools
import json
import math
import os
import pickle
import sys
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import Executor, Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from ..errors import GaussppError, InputError, SweepLogWarning, UnknownNameError
from .realizability_map import servo_margin
from .scene_cache import cached_scene
from .work_precision import Row, plan, score, work_precision_task

__all__ = [
    "SceneTask",
    "SweepError",
    "SweepResult",
    "cached_scene",
    "grid",
    "realizability_task",
    "simulate_task",
    "sweep",
    "work_precision",
    "work_precision_task",
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
    values = []
    for name, axis in axes.items():
        if not isinstance(axis, Iterable):
            raise InputError(f"grid axis {name}={axis!r} must be a list of values, e.g. {name}=[{axis!r}]")
        values.append(list(axis))
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


# -- columns --------------------------------------------------------------------------------------------
_MISSING = object()


def _numeric(values: list[Any]) -> np.ndarray | None:
    """Values (``_MISSING`` where absent) as one float array ``(N, *shape)``, NaN where absent; None if
    the present values are not numbers or arrays of one shape."""
    present = [v for v in values if v is not _MISSING]
    if any(isinstance(v, (str, bytes, Mapping)) for v in present):
        return None
    try:
        arrays = [np.asarray(v, dtype=float) for v in present]
    except (TypeError, ValueError):
        return None
    shapes = {a.shape for a in arrays}
    if len(shapes) > 1:
        return None
    shape = shapes.pop() if shapes else ()
    out = np.full((len(values), *shape), np.nan)
    it = iter(arrays)
    for i, v in enumerate(values):
        if v is not _MISSING:
            out[i] = next(it)
    return out


def _column_array(values: list[Any]) -> np.ndarray:
    """The best NPZ array for one column: int or bool if complete, float (NaN where absent), str, or JSON text."""
    present = [v for v in values if v is not _MISSING]
    complete = len(present) == len(values) and len(values) > 0
    if complete and all(isinstance(v, bool) for v in present):
        return np.array(present, dtype=bool)
    if complete and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        try:
            return np.array(present, dtype=np.int64)
        except OverflowError:
            pass
    if present and all(isinstance(v, str) for v in present):
        return np.array(["" if v is _MISSING else v for v in values], dtype=str)
    numeric = _numeric(values)
    if numeric is not None:
        return numeric
    return np.array(["" if v is _MISSING else _canonical(v, "a value") for v in values], dtype=str)


def _keys(dicts: Iterable[Mapping[str, Any] | None]) -> list[str]:
    return list(dict.fromkeys(k for d in dicts if d is not None for k in d))


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
        """``result[key]`` of every task as a float array, NaN where the task failed or lacks ``key``.

        Scalars give shape ``(N,)``; lists of one shape ``s`` (e.g. a final state) give ``(N, *s)``.
        """
        values = [_MISSING if r is None else r.get(key, _MISSING) for r in self.results]
        known = _keys(self.results)
        if known and key not in known:  # a typo (if every task failed, the column is all NaN)
            raise SweepError(f"no task's result has {key!r}; the results have {known}")
        out = _numeric(values)
        if out is None:
            raise SweepError(f"result {key!r} is not a number (or an array of one shape) in every task")
        return out

    def param(self, key: str) -> np.ndarray:
        """``params[key]`` of every task as an array (float, NaN where absent; or str)."""
        if not any(key in p for p in self.params):
            raise SweepError(f"no task has the parameter {key!r}; the parameters are {_keys(self.params)}")
        return _column_array([p.get(key, _MISSING) for p in self.params])

    def __len__(self) -> int:
        return len(self.params)

    # -- NPZ --------------------------------------------------------------------------------------------
    def to_npz(self, path: str | os.PathLike[str]) -> Path:
        """Write the sweep as NPZ columns, one array per parameter and per result key.

        Arrays: ``index``; ``ok`` (bool) and ``error`` (the error text, ``""`` where the task succeeded);
        ``params.<key>`` and ``results.<key>`` for every key — int or bool where complete, float with NaN
        where a task lacks the value or failed, ``(N, *shape)`` for lists of one shape, str for strings, the
        JSON text otherwise; ``record`` (the whole sweep as JSON, for :meth:`from_npz`). Loads with
        ``numpy.load(path)`` (no pickle).
        """
        target = Path(path)
        arrays: dict[str, np.ndarray] = {
            "index": np.arange(len(self), dtype=np.int64),
            "ok": np.array([i not in self.errors for i in range(len(self))], dtype=bool),
            "error": np.array([self.errors.get(i, "") for i in range(len(self))], dtype=str),
        }
        for key in _keys(self.params):
            arrays[f"params.{key}"] = _column_array([p.get(key, _MISSING) for p in self.params])
        for key in _keys(self.results):
            arrays[f"results.{key}"] = _column_array(
                [_MISSING if r is None else r.get(key, _MISSING) for r in self.results]
            )
        record = {
            "params": self.params,
            "results": self.results,
            "errors": {str(i): e for i, e in self.errors.items()},
            "wall_time": self.wall_time,
            "computed": self.computed,
        }
        arrays["record"] = np.array(_canonical(record, "the sweep"))
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            with target.open("wb") as fh:
                np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
        except OSError as exc:
            raise SweepError(f"cannot write {str(target)!r}: {exc}") from None
        return target

    @classmethod
    def from_npz(cls, path: str | os.PathLike[str]) -> SweepResult:
        """The sweep written by :meth:`to_npz`, exactly (params, results, errors)."""
        try:
            with np.load(Path(path), allow_pickle=False) as data:
                text = str(data["record"][()])
        except (OSError, ValueError) as exc:
            raise SweepError(f"cannot read {str(path)!r} as an NPZ file: {exc}") from None
        except KeyError:
            raise SweepError(f"{str(path)!r} is not a sweep written by SweepResult.to_npz (no 'record')") from None
        rec = json.loads(text)
        return cls(
            params=rec["params"],
            results=rec["results"],
            errors={int(i): e for i, e in rec["errors"].items()},
            wall_time=float(rec["wall_time"]),
            computed=int(rec["computed"]),
        )


# -- built-in tasks -----------------------------------------------------------------------------------
def realizability_task(params: Mapping[str, Any]) -> dict[str, float]:
    """The servo-torque realizability margin for one body axis ``n`` (see :mod:`gausspp.studies.realizability_map`).

    Parameters (keys of ``params``): ``lon``, ``lat`` — the direction of ``n`` in degrees;
    ``inertia`` (default ``(1, 2, 3)``) and ``l`` (default ``(1, 1, 1)``).
    Returns ``{"margin": ...}``.
    """
    lon, lat = math.radians(float(params["lon"])), math.radians(float(params["lat"]))
    n = (math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat))
    margin = servo_margin(params.get("inertia", (1.0, 2.0, 3.0)), params.get("l", (1.0, 1.0, 1.0)), n)
    return {"margin": float(margin)}


_SIMULATE_KEYS = ("scene", "t_end", "dt", "method", "solver", "rtol", "atol", "v_scale", "q0", "v0")


def _max_or_nan(x: np.ndarray) -> float:
    finite = np.asarray(x, dtype=float)
    finite = finite[~np.isnan(finite)]
    return float(np.max(finite)) if finite.size else math.nan


def simulate_task(params: Mapping[str, Any]) -> dict[str, Any]:
    """Simulate a scene and reduce the run to a few numbers: the default task of ``sweep("scene", ...)``.

    Parameters (keys of ``params``):

    - ``scene`` (default ``"pendulum"``; set by ``sweep("name", ...)``);
    - ``t_end`` (default: the scene's own horizon), ``method`` (default ``"rk4"``), ``dt`` (default
      ``t_end/2000`` for fixed-step methods, as ``gausspp run``; for adaptive ones, if given, the largest
      step), ``rtol``/``atol`` (adaptive methods; default 1e-9/1e-12), ``solver`` (default ``"direct"``);
      for the scenes beyond the direct formula (``gausspp.scenes.names("general")``: contacts, bounded or
      extra actuators, redundant rows) the defaults are ``"DOP853"`` and ``"qp"``;
    - initial data, for Monte Carlo sweeps on one model: ``q0``, ``v0`` (lists replacing the scene's
      initial configuration and velocity; they must satisfy the constraints) and ``v_scale`` (default 1:
      the initial velocity is multiplied by it, which keeps it on velocity-level constraints);
    - every other key is a scene parameter (``gausspp scenes NAME`` lists them).

    The model comes from :func:`cached_scene`, so it is built once per worker for every distinct set of
    scene parameters: vary the initial data through ``q0``/``v0``/``v_scale``, not through scene parameters,
    to keep one model.

    Returns
    -------
    dict
        ``t_final``, ``steps``; ``residual`` (the largest constraint residual ``|Φ|``, ``|g|``);
        ``energy_balance`` (the largest ``|ΔE − ΔW|``, zero for an exact motion; NaN if the model does not
        know its energy); ``max_reaction`` (the largest Euclidean norm of the generalized reaction
        ``R = [T] − F``); ``min_margin`` (the smallest realizability margin, NaN if undefined);
        ``q_end``, ``v_end`` (the final state, lists) and ``q_end_norm``; and ``q_error`` (the largest
        error of the final ``q`` against the scene's exact motion) where one is known and the run starts
        from the scene's own initial data within its horizon. A run that fails raises: the sweep records it.
    """
    from .. import scenes
    from ..simulation import methods
    from ..simulation.simulate import simulate

    scene_params = {k: v for k, v in params.items() if k not in _SIMULATE_KEYS}
    general = str(params.get("scene", "pendulum")) in scenes.names("general")  # contacts, bounds, redundancy
    method = methods.get(str(params.get("method", "DOP853" if general else "rk4")))
    dt = params.get("dt")
    scene = cached_scene(str(params.get("scene", "pendulum")), **scene_params)
    t_end = float(params.get("t_end", scene.t_end))
    if dt is None and not method.adaptive:  # as `gausspp run`; an adaptive method chooses its own steps
        dt = t_end / 2000
    own_data = "q0" not in params and "v0" not in params and float(params.get("v_scale", 1.0)) == 1.0
    q0 = np.asarray(params.get("q0", scene.q0), dtype=float)
    v0 = float(params.get("v_scale", 1.0)) * np.asarray(params.get("v0", scene.v0), dtype=float)
    traj = simulate(
        scene.model,
        q0,
        v0,
        t_end,
        dt=None if dt is None else float(dt),
        method=method.name,
        solver=str(params.get("solver", "qp" if general else "direct")),
        rtol=float(params.get("rtol", 1e-9)),
        atol=float(params.get("atol", 1e-12)),
        lam0=scene.lam0,
    )
    reaction = np.asarray(traj.reaction, dtype=float)
    out: dict[str, Any] = {
        "t_final": float(traj.t[-1]),
        "steps": float(traj.steps),
        "residual": float(traj.max_residual()),
        "energy_balance": _max_or_nan(np.abs(traj.energy_balance())),
        "max_reaction": _max_or_nan(np.linalg.norm(reaction, axis=-1)) if reaction.size else 0.0,
        "min_margin": -_max_or_nan(-np.asarray(traj.margin, dtype=float)),
        "q_end": [float(x) for x in traj.q[-1]],
        "v_end": [float(x) for x in traj.v[-1]],
        "q_end_norm": float(np.linalg.norm(traj.q[-1])),
    }
    if scene.exact is not None and own_data and traj.t[-1] <= scene.t_end * (1 + 1e-12):
        out["q_error"] = float(np.max(np.abs(traj.q[-1] - scene.exact(float(traj.t[-1]))[0])))
    return out


@dataclass(frozen=True)
class SceneTask:
    """The task of ``sweep("scene-name", ...)``: :func:`simulate_task` with ``scene`` fixed (picklable)."""

    scene: str

    def __call__(self, params: Mapping[str, Any]) -> dict[str, Any]:
        if params.get("scene", self.scene) != self.scene:
            raise InputError(f"a task of the {self.scene!r} sweep has scene={params['scene']!r}")
        return simulate_task({**params, "scene": self.scene})


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


def _task_name(task: Any) -> str:
    """A name for the task that is the same in every run of the same program (recorded in ``out``)."""
    if isinstance(task, SceneTask):
        return f"scene:{task.scene}"
    if isinstance(task, functools.partial):
        return f"partial({_task_name(task.func)})"
    target = task if hasattr(task, "__qualname__") else type(task)
    return f"{getattr(target, '__module__', '?')}.{getattr(target, '__qualname__', type(task).__name__)}"


def _read_out(path: Path, keys: list[str], task: str) -> dict[int, tuple[dict[str, Any] | None, str | None]]:
    """Records already in ``path``.

    An unterminated last line is the record a kill cut short: it is ignored (and cut off before the sweep
    appends, :func:`_open_log`). Any other line that is not a record (not JSON, no ``index``) is skipped
    with a :class:`~gausspp.SweepLogWarning` naming the file and the line: its task, if it had one, runs
    again, and the rest of the log is kept — resuming should not throw away good results because one line
    was damaged. Blank lines are skipped silently.
    """
    done: dict[int, tuple[dict[str, Any] | None, str | None]] = {}
    if not path.exists():
        return done
    try:
        fh = path.open(encoding="utf-8")
    except OSError as exc:
        raise SweepError(f"cannot read out={str(path)!r}: {exc}") from None
    with fh:
        for lineno, line in enumerate(fh, 1):
            if not line.strip() or not line.endswith("\n"):
                continue  # blank, or the partial last record of a killed sweep
            try:
                rec = json.loads(line)
                if isinstance(rec, dict) and "task" in rec and "index" not in rec:
                    if rec["task"] != task:
                        raise SweepError(
                            f"out={str(path)!r} holds a sweep of task {rec['task']!r}, not {task!r}: "
                            "use another out file or delete it"
                        )
                    continue
                index = int(rec["index"])
            except (ValueError, KeyError, TypeError, IndexError, OverflowError):
                warnings.warn(
                    f"out={str(path)!r} line {lineno} is not a record of this sweep ({line.strip()[:60]!r}); it is "
                    "skipped and its task, if it had one, runs again — delete the line to silence this",
                    SweepLogWarning,
                    stacklevel=3,
                )
                continue
            if not 0 <= index < len(keys) or _canonical(rec.get("params"), "params") != keys[index]:
                raise SweepError(
                    f"out={str(path)!r} line {lineno} records task {index} with other parameters than this sweep "
                    f"({rec.get('params')!r}); it holds another sweep: use another out file or delete it"
                )
            done[index] = (rec.get("result"), rec.get("error"))
    return done


def _cut_partial_line(path: Path) -> None:
    """Cut off an unterminated last line (a record a kill cut short; :func:`_read_out` ignored it)."""
    if not path.exists():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("rb+") as fh:
            fh.truncate(data.rfind(b"\n") + 1)


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


def _resolve_task(fn_or_scene: Any) -> Task:
    if isinstance(fn_or_scene, str):
        from .. import scenes

        if fn_or_scene not in scenes.names():
            raise UnknownNameError(
                f"sweep: {fn_or_scene!r} is neither a task function nor a scene; scenes: {scenes.names()}"
            )
        return SceneTask(fn_or_scene)
    if not callable(fn_or_scene):
        raise InputError(
            f"sweep: the first argument must be a task function (dict -> dict) or a scene name, "
            f"got {type(fn_or_scene).__name__}"
        )
    return fn_or_scene  # type: ignore[no-any-return]


def _paths(out: str | os.PathLike[str] | None) -> tuple[Path | None, Path | None]:
    """(JSON-lines log, NPZ file or None) for ``out``."""
    if out is None:
        return None, None
    path = Path(out)
    if path.suffix.lower() in (".parquet", ".pq"):
        raise SweepError(f"out={str(path)!r}: Parquet is not supported (it needs pyarrow); use a .npz or .jsonl file")
    if path.suffix.lower() == ".npz":
        return path.with_suffix(".jsonl"), path
    return path, None


def sweep(
    fn_or_scene: Task | str,
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
    fn_or_scene : callable ``dict -> dict of numbers``, or a scene name
        A top-level (picklable) function; it should get its model from :func:`cached_scene`. A scene
        name (``"pendulum"``) runs :func:`simulate_task` on that scene (see there for the parameters
        and the numbers it returns).
    params : list of dict
        JSON-serializable parameter dicts: :func:`grid` for a Cartesian product, or any list of samples.
    executor : None, "serial", a concurrent.futures.Executor, or a dask ``distributed.Client``
        Where the tasks run (see the module docstring). An executor passed in is left running.
    chunk : int, optional
        Tasks sent to a worker at once (default: about four chunks per worker, at most 256 tasks each).
    out : path, optional
        JSON-lines file: each finished task is appended as it arrives; tasks recorded there already are
        not run again (resume). A ``.npz`` path keeps that log as ``<stem>.jsonl`` beside it and also
        writes the finished sweep there as NPZ columns (:meth:`SweepResult.to_npz`).
    progress : bool
        Tasks done/total, tasks/s and the estimated time left on stderr.
    retry_failed : bool
        On resume, run again the tasks recorded as failed (default: keep their recorded error).

    Returns
    -------
    SweepResult
    """
    start = time.perf_counter()
    task = _resolve_task(fn_or_scene)
    plist = _param_list(params)
    keys = [_canonical(p, f"params[{i}]") for i, p in enumerate(plist)]
    executor = _checked_executor(executor, chunk, task)
    path, npz = _paths(out)
    name = _task_name(task)
    results, errors, todo = _resume(path, keys, name, retry_failed)
    sink = _open_log(path, name)
    collect = _Collector(plist, results, errors, sink, _Progress(len(todo), sys.stderr if progress else None))
    owned = executor is None and len(todo) > 0
    pool: Executor | str | None = ProcessPoolExecutor(max_workers=os.cpu_count()) if owned else executor
    try:
        _run(task, plist, todo, pool, chunk, collect)
    finally:
        if owned and isinstance(pool, Executor):
            pool.shutdown(wait=True, cancel_futures=True)
        if sink is not None:
            sink.close()
    res = SweepResult(
        params=plist,
        results=results,
        errors=dict(sorted(errors.items())),
        wall_time=time.perf_counter() - start,
        computed=len(todo),
    )
    if npz is not None:
        res.to_npz(npz)
    return res


def _param_list(params: Any) -> list[dict[str, Any]]:
    """``params`` as a list of parameter dicts (copies), or an InputError saying what it is instead."""
    if isinstance(params, (Mapping, str, bytes)) or not isinstance(params, Iterable):
        raise InputError(
            f"params must be a list of parameter dicts (e.g. grid(x=[1, 2])), got {type(params).__name__}"
            + ("; wrap a single point in a list" if isinstance(params, Mapping) else "")
        )
    plist: list[dict[str, Any]] = []
    for i, p in enumerate(params):
        if not isinstance(p, Mapping):
            raise InputError(f"params[{i}] must be a dict of parameters, got {type(p).__name__} {p!r}")
        plist.append(dict(p))
    return plist


def _checked_executor(executor: Any, chunk: int | None, task: Task) -> Executor | str | None:
    """``executor`` checked (a dask Client becomes its executor), ``chunk`` checked, and ``task`` checked to
    be picklable when it goes to worker processes."""
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
                f"the task {_task_name(task)} cannot be sent to worker processes ({type(exc).__name__}: {exc}); "
                "define it as a top-level function of a module (not a lambda or a nested function), "
                "or use executor='serial'"
            ) from None
    return executor  # type: ignore[no-any-return]


def _resume(
    path: Path | None, keys: list[str], name: str, retry_failed: bool
) -> tuple[list[dict[str, Any] | None], dict[int, str], list[int]]:
    """The results and errors already recorded in ``path`` (in task order), and the tasks still to run."""
    results: list[dict[str, Any] | None] = [None] * len(keys)
    errors: dict[int, str] = {}
    recorded = _read_out(path, keys, name) if path is not None else {}
    for index, (result, error) in recorded.items():
        if error is not None and retry_failed:
            continue
        results[index] = result
        if error is not None:
            errors[index] = error
    todo = [i for i in range(len(keys)) if i not in recorded or (retry_failed and recorded[i][1] is not None)]
    return results, errors, todo


def _open_log(path: Path | None, name: str) -> TextIO | None:
    """The JSON-lines log opened for appending (its first line names the task), a partial last line cut off."""
    if path is None:
        return None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _cut_partial_line(path)  # a kill's partial last record must not swallow the next one
        sink = path.open("a", encoding="utf-8")
    except OSError as exc:
        raise SweepError(f"cannot write out={str(path)!r}: {exc}") from None
    if sink.tell() == 0:
        sink.write(_canonical({"task": name}, "the task's name") + "\n")
    sink.flush()
    return sink


@dataclass
class _Collector:
    """Takes each finished chunk: into ``results`` and ``errors``, appended to the log, counted by the bar."""

    plist: list[dict[str, Any]]
    results: list[dict[str, Any] | None]
    errors: dict[int, str]
    sink: TextIO | None
    bar: _Progress

    def __call__(self, batch: list[tuple[int, str | None, str | None]]) -> None:
        for index, result_json, error in batch:
            result = json.loads(result_json) if result_json is not None else None
            self.results[index] = result
            if error is not None:
                self.errors[index] = error
            else:
                self.errors.pop(index, None)
            if self.sink is not None:
                record = {"index": index, "params": self.plist[index]}
                record.update({"error": error} if error is not None else {"result": result})
                self.sink.write(_canonical(record, "record") + "\n")
        if self.sink is not None:
            self.sink.flush()  # in the OS's hands: survives a kill of this process
        self.bar.update(len(batch), sum(e is not None for _, _, e in batch))


def _run(
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
            collect(_run_chunk(task, [(i, plist[i]) for i in todo[k : k + size]]))
        return
    assert isinstance(pool, Executor)
    size = chunk or max(1, min(256, math.ceil(len(todo) / (4 * _workers(pool)))))
    futures: list[Future[Any]] = [
        pool.submit(_run_chunk, task, [(i, plist[i]) for i in todo[k : k + size]]) for k in range(0, len(todo), size)
    ]
    try:
        for fut in as_completed(futures):
            collect(fut.result())
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise


# -- the work-precision study as a sweep ---------------------------------------------------------------
def work_precision(
    scene_names: Sequence[str] | None = None,
    method_names: Sequence[str] | None = None,
    solvers: Sequence[str] | None = None,
    *,
    quick: bool = True,
    repeats: int = 2,
    samples: int = 21,
    executor: Executor | str | Any | None = None,
    out: str | os.PathLike[str] | None = None,
    progress: bool = True,
) -> tuple[list[Row], SweepResult]:
    """:func:`gausspp.report.work_precision` as a sweep: one task per reference and per run.

    The same arguments and the same rows (in the same order; only the wall times differ — they are
    measured in the workers, side by side, so they are noisier than one run after the other), plus the
    sweep (``out`` is its resumable JSON-lines log; ``executor``, ``progress`` as in :func:`sweep`).
    Each scene's reference is computed once, by one task.
    """
    params = plan(scene_names, method_names, solvers, quick, repeats, samples)
    res = sweep(work_precision_task, params, executor=executor, chunk=1, out=out, progress=progress)
    return score(res.params, res.results, res.errors), res
