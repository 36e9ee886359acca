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
import math
import os
import sys
import time
import warnings
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError, SweepWarning, UnknownNameError
from ..validation import flag
from .realizability_map import servo_margin
from .scene_cache import cached_scene
from .sweep_engine import Progress, Task, checked_executor, run_tasks
from .sweep_log import Collector, log_paths, open_log, resume
from .sweep_result import SweepError, SweepResult, canonical_json
from .work_precision import Row, plan, score, work_precision_task

if TYPE_CHECKING:
    from ..scenes.scene import Scene
    from ..simulation.trajectory import Trajectory

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


# -- parameters ---------------------------------------------------------------------------------------
def grid(**axes: Iterable[Any]) -> list[dict[str, Any]]:
    """The Cartesian product of the axes, as a list of parameter dicts (the first axis varies slowest).

    >>> grid(a=[1, 2], b=["x", "y"])
    [{'a': 1, 'b': 'x'}, {'a': 1, 'b': 'y'}, {'a': 2, 'b': 'x'}, {'a': 2, 'b': 'y'}]
    """
    names = list(axes)
    values = []
    for name, axis in axes.items():
        if not isinstance(axis, Iterable) or isinstance(axis, (str, bytes, dict)):
            raise InputError(f"grid axis {name}={axis!r} must be a list of values, e.g. {name}=[{axis!r}]")
        values.append(list(axis))
        if not values[-1]:
            raise InputError(f"grid axis {name}=[] is empty: the grid would have no point; give it at least one value")
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*values)]


# -- built-in tasks -----------------------------------------------------------------------------------
def realizability_task(params: Mapping[str, Any]) -> dict[str, float]:
    """The servo-torque realizability margin for one body axis ``n`` (see :mod:`gausspp.studies.realizability_map`).

    Parameters (keys of ``params``): ``lon``, ``lat`` — the direction of ``n`` in degrees;
    ``inertia`` (default ``(1, 2, 3)``) and ``l`` (default ``(1, 1, 1)``).
    Returns ``{"margin": ...}``.
    """
    lon, lat = (math.radians(_number(params, key, "realizability_task")) for key in ("lon", "lat"))
    n = (math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat))
    margin = servo_margin(params.get("inertia", (1.0, 2.0, 3.0)), params.get("l", (1.0, 1.0, 1.0)), n)
    return {"margin": float(margin)}


_SIMULATE_KEYS = ("scene", "t_end", "dt", "method", "solver", "rtol", "atol", "v_scale", "q0", "v0")


def _max_or_nan(x: np.ndarray) -> float:
    finite = np.asarray(x, dtype=float)
    finite = finite[~np.isnan(finite)]
    return float(np.max(finite)) if finite.size else math.nan


_MISSING = object()


def _number(params: Mapping[str, Any], key: str, task: str, default: Any = _MISSING) -> float:
    """``params[key]`` as a float (``default`` if absent); a missing or non-numeric value is a project error naming the
    task and the parameter."""
    if key not in params and default is _MISSING:
        raise InputError(f"{task}: the parameter {key!r} is missing; give it in each point of the sweep")
    value = params.get(key, default)
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{task}: the parameter {key}={value!r} must be a number") from None
    if not math.isfinite(number):
        raise InputError(f"{task}: the parameter {key}={value!r} must be finite")
    return number


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
    scene, traj, own_data = _simulated(params)
    return _run_numbers(scene, traj, own_data)


def _simulated(params: Mapping[str, Any]) -> tuple[Scene, Trajectory, bool]:
    """The scene (from :func:`cached_scene`), its simulated trajectory with the settings of ``params`` (see
    :func:`simulate_task`), and whether the run starts from the scene's own initial data."""
    from .. import scenes
    from ..simulation import methods
    from ..simulation.simulate import simulate

    scene_params = {k: v for k, v in params.items() if k not in _SIMULATE_KEYS}
    general = str(params.get("scene", "pendulum")) in scenes.names("general")  # contacts, bounds, redundancy
    method = methods.get(str(params.get("method", "DOP853" if general else "rk4")))
    dt = _number(params, "dt", "simulate_task") if params.get("dt") is not None else None
    scene = cached_scene(str(params.get("scene", "pendulum")), **scene_params)
    t_end = _number(params, "t_end", "simulate_task", scene.t_end)
    if dt is None and not method.adaptive:  # as `gausspp run`; an adaptive method chooses its own steps
        dt = t_end / 2000
    v_scale = _number(params, "v_scale", "simulate_task", 1.0)
    own_data = "q0" not in params and "v0" not in params and v_scale == 1.0
    q0 = np.asarray(params.get("q0", scene.q0), dtype=float)
    v0 = v_scale * np.asarray(params.get("v0", scene.v0), dtype=float)
    traj = simulate(
        scene.model,
        q0,
        v0,
        t_end,
        dt=dt,
        method=method.name,
        solver=str(params.get("solver", "qp" if general else "direct")),
        rtol=_number(params, "rtol", "simulate_task", 1e-9),
        atol=_number(params, "atol", "simulate_task", 1e-12),
        lam0=scene.lam0,
    )
    return scene, traj, own_data


def _run_numbers(scene: Scene, traj: Trajectory, own_data: bool) -> dict[str, Any]:
    """The numbers :func:`simulate_task` returns for the run ``traj`` of ``scene``."""
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
def _task_name(task: Any) -> str:
    """A name for the task that is the same in every run of the same program (recorded in ``out``)."""
    if isinstance(task, SceneTask):
        return f"scene:{task.scene}"
    if isinstance(task, functools.partial):
        return f"partial({_task_name(task.func)})"
    target = task if hasattr(task, "__qualname__") else type(task)
    return f"{getattr(target, '__module__', '?')}.{getattr(target, '__qualname__', type(task).__name__)}"


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
    progress = flag("sweep", "progress", progress)
    retry_failed = flag("sweep", "retry_failed", retry_failed)
    task = _resolve_task(fn_or_scene)
    plist = _param_list(params)
    keys = [canonical_json(p, f"params[{i}]") for i, p in enumerate(plist)]
    name = _task_name(task)
    executor = checked_executor(executor, chunk, task, name)
    path, npz = log_paths(out)
    results, errors, todo = resume(path, keys, name, retry_failed)
    sink = open_log(path, name)
    collect = Collector(plist, results, errors, sink, Progress(len(todo), sys.stderr if progress else None))
    try:
        _run_surviving(task, plist, todo, executor, chunk, collect, results, errors)
    finally:
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
    if plist and len(res.errors) == len(plist):
        first = next(iter(res.errors.values()))
        warnings.warn(
            f"every one of the {len(plist)} tasks failed (the first: {first.strip().splitlines()[-1][:200]}); "
            "SweepResult.errors holds each error — check the task and its parameters on one point first",
            SweepWarning,
            stacklevel=2,
        )
    return res


#: How many times a local pool whose worker died is restarted within one sweep before the sweep gives up.
POOL_RESTARTS = 3


def _run_surviving(
    task: Task,
    plist: list[dict[str, Any]],
    todo: list[int],
    executor: Executor | str | None,
    chunk: int | None,
    collect: Collector,
    results: list[dict[str, Any] | None],
    errors: dict[int, str],
) -> None:
    """:func:`run_tasks`; the local pool (``executor=None``) restarted when a worker dies (killed, out of memory)
    and the tasks not yet collected sent again, up to :data:`POOL_RESTARTS` times. A pool the caller passed, or one
    that keeps dying, ends the sweep in a :class:`SweepError` that says how many tasks are done (recorded in
    ``out``, if given) and that the same call resumes."""
    owned, restarts = executor is None, 0
    while True:
        remaining = [i for i in todo if results[i] is None and i not in errors]
        if not remaining:
            return
        pool: Executor | str | None = ProcessPoolExecutor(max_workers=os.cpu_count()) if owned else executor
        try:
            run_tasks(task, plist, remaining, pool, chunk, collect)
            return
        except BrokenProcessPool as exc:
            restarts += 1
            done = sum(1 for i in todo if results[i] is not None or i in errors)
            if not owned or restarts > POOL_RESTARTS:
                given = "the executor passed in" if not owned else f"the local pool, {POOL_RESTARTS} restarts"
                raise SweepError(
                    f"a worker process died ({given}): {done} of {len(todo)} tasks are done and recorded; the "
                    "same call (with out=) resumes the others"
                ) from exc
        finally:
            if owned and isinstance(pool, Executor):
                pool.shutdown(wait=True, cancel_futures=True)


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
