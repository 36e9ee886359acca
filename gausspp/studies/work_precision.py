"""The work-precision study (error against run time), written once: its plan, its task, its scoring.

The study runs, for each scene, each method over a sweep (fixed-step methods over ``dt``, adaptive
ones over ``rtol``) and each step solver, records the state at common sample times, and scores it
against the scene's exact solution — or, where a scene has none, against a reference by a different
method at a much finer setting (compiled RK4 with ≈1.6·10⁵ steps, cross-checked by DOP853 at
``rtol = 1e-13``; the row says which). Errors are mixed absolute/relative,
``max |x − x_ref| / max(1, |x_ref|)`` over ``q`` and ``v``, and are also given as significant correct
digits ``−log₁₀`` (the Bari test set's scoring). Wall time is the minimum of several runs.

It is a list of independent tasks (:func:`plan`): one reference per scene, then one run per
(scene, method, solver, setting), each done by :func:`work_precision_task`; :func:`score` turns their
results into :class:`Row`\\ s. :func:`gausspp.sweeps.work_precision` runs the tasks on any executor,
:func:`gausspp.report.work_precision` in this process.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import scenes
from ..errors import GaussppError, InputError, UnknownNameError
from ..simulation import lanes
from ..simulation import methods as _methods
from ..simulation.simulate import simulate
from ..step import qp
from .scene_cache import cached_scene

#: Horizon cap (the long-horizon behaviour is the stability study's business).
HORIZON = 1.0

#: Scene parameters for the study where the defaults are too easy (a polynomial exact motion).
STUDY_PARAMS: dict[str, dict[str, Any]] = {"two-masses": {"realization": "servo", "k": 3.0, "v": 0.5}}

#: The methods and step solvers of the study unless told otherwise.
METHODS = ("rk4", "DOP853", "Radau", "cvodes")


def default_solvers() -> list[str]:
    """The step solvers of the study unless told otherwise: the direct formula and two QP backends."""
    return ["direct", qp.DEFAULT, "casadi:osqp"]


@dataclass(frozen=True)
class Row:
    """One run of the study."""

    scene: str
    method: str
    solver: str
    setting: str
    final_error: float
    max_error: float
    digits: float
    reference: str
    constraint_residual: float
    energy_error: float
    wall_time: float
    steps: int
    rhs_evaluations: int
    status: str
    message: str


@dataclass(frozen=True)
class Reference:
    """The states a run is scored against, at the common sample times."""

    t: np.ndarray
    x: np.ndarray
    source: str


def mixed_error(x: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """``max |x − ref| / max(1, |ref|)`` over the last axis."""
    return np.max(np.abs(x - ref) / np.maximum(1.0, np.abs(ref)), axis=-1)


def reference(scene: scenes.Scene, t: np.ndarray) -> Reference:
    """The exact solution, or compiled RK4 with ≈1.6·10⁵ steps checked against DOP853 at rtol 1e-13."""
    if scene.exact is not None:
        return Reference(t, np.array([np.concatenate(scene.exact(ti)) for ti in t]), "exact")
    T = float(t[-1])
    steps = (t.size - 1) * 2**13  # ≈ 1.6·10⁵ steps, the samples on the grid
    common: dict[str, Any] = dict(lam0=scene.lam0, solver="direct", record=t)
    fine = simulate(scene.model, scene.q0, scene.v0, T, method="rk4", lane="compiled", dt=T / steps, **common)
    check = simulate(scene.model, scene.q0, scene.v0, T, method="DOP853", rtol=1e-13, atol=1e-15, **common)
    x = np.hstack([fine.q, fine.v])
    spread = float(mixed_error(np.hstack([check.q, check.v]), x).max())
    return Reference(t, x, f"rk4 (compiled) {steps} steps (DOP853 1e-13 agrees to {spread:.0e})")


def settings(method: _methods.Method, T: float, samples: int, quick: bool) -> list[tuple[str, dict[str, Any]]]:
    """The method's sweep: ``(label, options)`` over ``rtol`` (adaptive) or over ``dt`` dividing the sampling."""
    if method.adaptive:
        tols = [1e-4, 1e-7, 1e-10, 1e-13] if quick else [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13]
        return [(f"rtol={r:g}", {"rtol": r, "atol": r * 1e-2}) for r in tols]
    base = T / (samples - 1)  # dt divides the sampling interval, so the samples lie on the grid
    factors = [4, 32, 256] if quick else [1, 4, 16, 64, 256, 1024]
    if lanes.lane_of(method, lanes.KINDS[lanes.SMOOTH]).name == "python":
        factors = factors[:2]  # one Python call per stage: the fine end belongs to the compiled lane
    return [(f"dt=T/{(samples - 1) * f}", {"dt": base / f}) for f in factors]


def best_of(repeats: int, run: Callable[[], Any]) -> tuple[float, Any]:
    """The smallest wall time of ``repeats`` calls of ``run``, and the last call's result."""
    best, result = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return best, result


def study_scene(name: str) -> Any:
    """The scene as the study builds it (:data:`STUDY_PARAMS`), once per process."""
    return cached_scene(name, **STUDY_PARAMS.get(name, {}))


def study_times(scene: Any, samples: int) -> np.ndarray:
    """The common sample times: ``samples`` uniform times up to ``min(t_end, HORIZON)``."""
    return np.linspace(0.0, min(scene.t_end, HORIZON), samples)


def _simulate_run(scene: Any, t: np.ndarray, params: Mapping[str, Any]) -> tuple[float, Any]:
    """One run of the study's task, the best wall time of ``repeats``."""
    solver = str(params["solver"])
    kind: dict[str, Any] = {"solver": "direct"} if solver == "direct" else {"solver": "qp", "backend": solver}
    opts = dict(params["options"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return best_of(
            int(params["repeats"]),
            lambda: simulate(
                scene.model,
                scene.q0,
                scene.v0,
                float(t[-1]),
                lam0=scene.lam0,
                method=str(params["method"]),
                record=t,
                **kind,
                **opts,
            ),
        )


def work_precision_task(params: Mapping[str, Any]) -> dict[str, Any]:
    """One task of the study: a scene's reference, or one run (method, solver, setting).

    ``{"task": "reference", "scene", "samples"}`` returns the reference states ``x`` (``q`` then ``v``)
    at the sample times and their ``source``; ``{"task": "run", "scene", "method", "solver", "setting",
    "options", "samples", "repeats"}`` runs :func:`gausspp.simulate` (the best wall time of ``repeats``)
    and returns the sampled states ``x`` with the run's figures (``status``, ``message``, ``solver``,
    ``constraint_residual``, ``energy_error``, ``wall_time``, ``steps``, ``rhs_evaluations``).
    :func:`score` scores the runs against the reference.
    """
    scene = study_scene(str(params["scene"]))
    t = study_times(scene, int(params["samples"]))
    if params["task"] == "reference":
        ref = reference(scene, t)
        return {"x": ref.x.tolist(), "source": ref.source}
    if params["task"] != "run":
        raise InputError(f"work_precision_task: task={params['task']!r} is neither 'reference' nor 'run'")
    try:
        wall, traj = _simulate_run(scene, t, params)
    except GaussppError as exc:
        return {"status": "failed", "message": f"{type(exc).__name__}: {exc}"}
    balance = traj.energy_balance()
    energy = float(np.nanmax(np.abs(balance))) if np.isfinite(balance).any() else math.nan
    return {
        "x": np.hstack([traj.q, traj.v]).tolist(),
        "solver": traj.solver,
        "constraint_residual": float(traj.max_residual()),
        "energy_error": energy,
        "wall_time": float(wall),
        "steps": int(traj.steps),
        "rhs_evaluations": int(traj.rhs_evaluations),
        "status": traj.status,
        "message": traj.message,
    }


def _checked(
    scene_names: Sequence[str] | None,
    method_names: Sequence[str] | None,
    solvers: Sequence[str] | None,
    repeats: int,
    samples: int,
) -> tuple[list[str], list[_methods.Method], list[str]]:
    """The study's scenes, methods and solvers (defaults filled in), every name and number checked."""
    names = list(scene_names or scenes.names("equality"))  # the scenes with the direct formula
    for name in names:
        if name not in scenes.names():
            raise UnknownNameError(f"scene {name!r} is unknown; available: {scenes.names()}")
    meths = [_methods.get(m) for m in (method_names or METHODS)]
    solver_list = list(solvers or default_solvers())
    for solver in solver_list:
        if solver != "direct" and solver not in qp.names():
            raise UnknownNameError(f"solver {solver!r} is unknown; use 'direct' or a QP backend: {qp.names()}")
    if isinstance(repeats, bool) or not isinstance(repeats, int) or repeats < 1:
        raise InputError(f"repeats must be a positive integer, got {repeats!r}")
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 2:
        raise InputError(f"samples must be an integer ≥ 2, got {samples!r}")
    return names, meths, solver_list


def plan(
    scene_names: Sequence[str] | None,
    method_names: Sequence[str] | None,
    solvers: Sequence[str] | None,
    quick: bool,
    repeats: int,
    samples: int,
) -> list[dict[str, Any]]:
    """The study's tasks (parameters of :func:`work_precision_task`): the references first (the longest
    tasks start at once), then every run, scene by scene, method by method, solver by solver."""
    names, meths, solver_list = _checked(scene_names, method_names, solvers, repeats, samples)
    refs: list[dict[str, Any]] = [{"task": "reference", "scene": name, "samples": samples} for name in names]
    runs: list[dict[str, Any]] = []
    for name in names:
        T = float(study_times(study_scene(name), samples)[-1])
        for meth in meths:
            for solver in solver_list:
                if not lanes.accepts(meth, "direct" if solver == "direct" else "qp"):
                    continue  # e.g. CVODES differentiates the right-hand side: the direct step only
                for setting, opts in settings(meth, T, samples, quick):
                    runs.append(
                        {"task": "run", "scene": name, "method": meth.name, "solver": solver, "setting": setting}
                        | {"options": opts, "samples": samples, "repeats": repeats}
                    )
    return refs + runs


def _failed(p: Mapping[str, Any], source: str, message: str) -> Row:
    nan = math.nan
    return Row(
        p["scene"], p["method"], p["solver"], p["setting"], nan, nan, nan, source, nan, nan, nan, 0, 0,
        "failed", message,
    )  # fmt: skip


def _scored(p: Mapping[str, Any], r: Mapping[str, Any], ref_x: np.ndarray, source: str) -> Row:
    err = mixed_error(np.asarray(r["x"], dtype=float), ref_x)
    final = float(err[-1])
    return Row(
        p["scene"],
        p["method"],
        str(r["solver"]),
        p["setting"],
        final,
        float(err.max()),
        float(-np.log10(max(final, 1e-17))),
        source,
        float(r["constraint_residual"]),
        float(r["energy_error"]),
        float(r["wall_time"]),
        int(r["steps"]),
        int(r["rhs_evaluations"]),
        str(r["status"]),
        str(r["message"]),
    )


def score(
    params: Sequence[Mapping[str, Any]], results: Sequence[Mapping[str, Any] | None], errors: Mapping[int, str]
) -> list[Row]:
    """The study's rows from its tasks' ``results`` (``None`` where a task raised; ``errors`` says why):
    each run scored against its scene's reference; a failed run, task or reference gives a failed row."""
    refs: dict[str, tuple[np.ndarray | None, str]] = {}
    for i, (p, r) in enumerate(zip(params, results, strict=True)):
        if p["task"] == "reference":
            refs[p["scene"]] = (
                (np.asarray(r["x"], dtype=float), str(r["source"]))
                if r is not None
                else (None, f"reference failed: {errors.get(i, '?')}")
            )
    rows: list[Row] = []
    for i, (p, r) in enumerate(zip(params, results, strict=True)):
        if p["task"] != "run":
            continue
        ref_x, source = refs[p["scene"]]
        if r is None:  # the task raised something the study does not catch
            rows.append(_failed(p, source, f"task failed: {errors.get(i, '?')}"))
        elif r["status"] == "failed" and "x" not in r:
            rows.append(_failed(p, source, str(r["message"])))
        elif ref_x is None:
            rows.append(_failed(p, source, source))
        elif np.shape(r["x"]) != ref_x.shape:
            rows.append(_failed(p, source, f"{r['status']}: {r['message']}"))
        else:
            rows.append(_scored(p, r, ref_x, source))
    return rows


def describe(params: Mapping[str, Any]) -> str:
    """One task in words (for progress lines): ``pendulum: reference`` or ``pendulum: rk4 with direct, dt=…``."""
    if params["task"] == "reference":
        return f"{params['scene']}: reference"
    return f"{params['scene']}: {params['method']} with {params['solver']}, {params['setting']}"
