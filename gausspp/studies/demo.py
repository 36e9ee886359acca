"""The demo's content (``gausspp demo``): one step by both solvers, every scene by both step solvers,
the scenes only the general Gauss QP solves, and the teaching figures.

Each study yields its rows one at a time (the command line prints each as soon as it is computed);
:mod:`gausspp.studies.tables` turns them into text.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import plot, scenes
from ..model.model import Model
from ..simulation.simulate import simulate
from ..simulation.trajectory import Trajectory
from ..step import general as general_step
from ..step.qp import qpsolvers_backend
from ..verification.crosscheck import crosscheck
from ..verification.verify import verify
from .figures import skate_runs, skate_title, suslov_steady, three_realizations_runs
from .realizability_map import realizability_grid

#: The one-step cases: the two masses with a rod and with a servo, the rigid body with Suslov's and a servo's axis.
STEP_CASES: tuple[tuple[str, dict[str, Any]], ...] = (
    ("two-masses", {"realization": "ideal"}),
    ("two-masses", {"realization": "servo"}),
    ("rigid-body-servo", {}),
    ("rigid-body-servo", {"n": (1.0, 0.2, 0.0)}),
)

#: Steps of compiled RK4 per scene in the demo (stiff or fast scenes need more).
STEPS = {"stiff-chain": 20_000, "andrews": 4_000}

#: The general-QP rows' horizon where the scene's own (≤ 3 s) costs too much for the demo (each right-hand
#: side is a Gauss QP solved from Python): the four-bar's redundant rows are there from the start; the crane
#: runs with the weaker motor of :data:`GENERAL_PARAMS`, which saturates before t = 1; the parallelogram (A02) stops
#: before its first collinear position (t ≈ 0.708), where its pin rows drop rank.
#: The general-QP rows' tolerance (each right-hand side is a QP solved from Python, costly: 1e-10 rather than
#: 1e-11 takes fewer steps, and keeps the two backends' gap far below the table's 1e-8 claims).
GENERAL_RTOL = 1e-10

GENERAL_T_END = {
    "saturated-crane": 1.0,
    "four-bar-redundant": 0.25,
    "parallelogram": 0.5,
    "spatial-parallelogram": 0.5,
}

#: Scene parameters of the general-QP rows: a crane motor of 8 N (12 by default) saturates within the first second.
GENERAL_PARAMS: dict[str, dict[str, Any]] = {"saturated-crane": {"F_max": 8.0}}


@dataclass(frozen=True)
class StepRow:
    """One solver's raw step at t = 0 (no refinement), its gap to the direct one and to the reference, its cost."""

    scene: str
    label: str
    solver: str
    acceleration: np.ndarray
    multiplier: float
    gap: float | None  # QP vs direct (None on the direct row)
    versus_reference: float
    us_per_step: float


@dataclass(frozen=True)
class SceneRow:
    """One scene by compiled RK4 with the direct step and with the QP, verified by (23)."""

    scene: str
    realizations: str
    t_end: float
    steps: int
    gap: float
    residual: float
    energy_balance: float | None
    relative_gap: float
    is_motion: bool
    run_ms: float


@dataclass(frozen=True)
class GeneralRow:
    """One scene beyond the closed forms, by the general Gauss QP."""

    scene: str
    what: str
    t_end: float
    events: int
    saturated: float | None
    backend_gap: float | None
    residual: float
    energy_balance: float | None
    exact_error: float | None
    run_ms: float


@dataclass(frozen=True)
class Backends:
    """The qpsolvers backends of the general-QP table: the default one, and a second to compare it with."""

    first: str
    second: str | None


def time_per_step(model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, solver: str) -> float:
    """Minimum over repeats of the compiled kernel's time per step, in µs."""
    kernel = model.kernel(solver)
    kernel.inputs[0][0] = t
    kernel.inputs[1][:], kernel.inputs[2][:], kernel.inputs[3][:] = q, v, lam
    calls, best = 2000, np.inf
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(calls):
            kernel.evaluate()
        best = min(best, (time.perf_counter() - start) / calls)
    return best * 1e6


def _step_label(scene: scenes.Scene, params: dict[str, Any]) -> str:
    return params.get("realization") or (
        "Suslov (n = l)"
        if scene.params.get("suslov")
        else "servo n=(" + ", ".join(f"{x:.2f}" for x in scene.params["n"]) + ")"
    )


def step_pair(case: int) -> tuple[StepRow, StepRow]:
    """Case ``case`` of :data:`STEP_CASES` by the direct formula and by the Gauss QP (raw answers), against the
    independent acceleration-space QP (:func:`gausspp.crosscheck`), with the compiled time per step."""
    name, params = STEP_CASES[case]
    scene = scenes.get(name, **params)
    model = scene.model
    lam = scene.lam0 if scene.lam0 is not None else np.zeros(0)
    direct = model.step(0.0, scene.q0, scene.v0, solver="direct", refine=False)
    gauss = model.step(0.0, scene.q0, scene.v0, solver="qp", refine=False)
    check = crosscheck(model, 0.0, scene.q0, scene.v0, scene.lam0)
    rows = [
        StepRow(
            scene=name,
            label=_step_label(scene, params),
            solver=solver,
            acceleration=res.a,
            multiplier=float(res.u[0]),
            gap=None if solver == "direct" else gauss.disagreement(direct),
            versus_reference=check.distances["direct" if solver == "direct" else "qp:default"],
            us_per_step=time_per_step(model, 0.0, scene.q0, scene.v0, lam, solver),
        )
        for res, solver in ((direct, "direct"), (gauss, "qp"))
    ]
    return rows[0], rows[1]


def step_rows() -> Iterator[StepRow]:
    """Every case of :data:`STEP_CASES` (:func:`step_pair`), direct row then QP row."""
    for case in range(len(STEP_CASES)):
        yield from step_pair(case)


def _largest_energy_balance(traj: Trajectory) -> float | None:
    """The largest ``|ΔE − W|`` along the run; ``None`` if the model does not know its energy."""
    balance = np.abs(traj.energy_balance())
    return float(np.nanmax(balance)) if np.isfinite(balance).any() else None


def scene_row(name: str) -> SceneRow:
    """Scene ``name`` with the direct formula, by compiled RK4 with the direct step and with the QP (T ≤ 2),
    the largest relative state difference along the run, and the direct run verified by (23)."""
    scene = scenes.get(name)
    T = min(scene.t_end, 2.0)
    steps = STEPS.get(name, 2000)
    kwargs: dict[str, Any] = dict(
        lam0=scene.lam0, method="rk4", lane="compiled", dt=T / steps, record=max(steps // 400, 1)
    )
    start = time.perf_counter()
    direct = simulate(scene.model, scene.q0, scene.v0, T, solver="direct", **kwargs)
    run_ms = (time.perf_counter() - start) * 1e3
    gauss = simulate(scene.model, scene.q0, scene.v0, T, solver="qp", **kwargs)
    scale = max(1.0, float(np.abs(np.hstack([direct.q, direct.v])).max()))
    check = verify(scene.model, direct)
    return SceneRow(
        scene=name,
        realizations=", ".join(dict.fromkeys(c.realization.label for c in scene.model.constraints)),
        t_end=T,
        steps=direct.steps,
        gap=float(np.abs(np.hstack([gauss.q - direct.q, gauss.v - direct.v])).max()) / scale,
        residual=direct.max_residual(),
        energy_balance=_largest_energy_balance(direct),
        relative_gap=check.relative_gap,
        is_motion=check.is_motion,
        run_ms=run_ms,
    )


def scene_rows() -> Iterator[SceneRow]:
    """Every scene with the direct formula (:func:`scene_row`)."""
    for name in scenes.names("equality"):
        yield scene_row(name)


def backends() -> Backends:
    """The general QP's default backend (casadi's qrqp, compiled into the step) and one to compare it with: ProxQP
    when installed (a proximal augmented Lagrangian method against an active set), else OSQP — none when that is
    the default itself. (ProxQP before OSQP: at these rows' tolerances OSQP, iterative, is the slower;
    ``benchmarks/general_qp.py`` prints OSQP's time per QP beside daqp's.)"""
    first = general_step.default_backend()
    second = "proxqp" if "proxqp" in qpsolvers_backend.available() else "osqp"
    return Backends(first, None if first in ("osqp", second) else second)


def _registry_name(backend: str) -> str:
    """A backend's short name as the registry's full name (a qpsolvers solver unless it names its family)."""
    return backend if ":" in backend or backend == general_step.default_backend() else f"qpsolvers:{backend}"


def _features(model: Model, traj: Trajectory) -> str:
    """What makes the scene need the general QP: contacts, bounds, extra actuators, redundant rows."""
    redundant = traj.solver.startswith("gauss-qp") and not (model.bounded or model.contacts or model.m > model.k)
    features = [
        f"{len(model.contacts)} contact(s)" if model.contacts else "",
        "bounded" if model.bounded else "",
        f"{model.m} actuators, {model.k} row(s)" if model.m > model.k else "",
        "redundant rows" if redundant else "",
    ]
    # otherwise its rows are independent but for isolated instants (a parallelogram's collinear positions)
    return ", ".join(f for f in features if f) or "rank drops at instants"


def _on_grid_gap(run: Trajectory, other: Trajectory, grid: np.ndarray) -> float:
    """Largest difference of ``q`` between two runs at the times of ``grid`` (the later sample of an impact)."""
    on_grid = [np.flatnonzero(np.isin(tr.t, grid) & np.r_[np.diff(tr.t) > 0, True]) for tr in (run, other)]
    return float(np.abs(run.q[on_grid[0]] - other.q[on_grid[1]]).max())


@dataclass(frozen=True)
class GeneralRun:
    """One general-QP scene run on one backend (a task of its own: the two backends run side by side)."""

    trajectory: Trajectory
    run_ms: float


def general_run(name: str, backend: str) -> GeneralRun:
    """Scene ``name`` (without a closed-form step) by DOP853 (rtol :data:`GENERAL_RTOL`) with the general Gauss QP
    on the qpsolvers ``backend``, recorded at 201 times, to ``T = min(t_end, GENERAL_T_END)``
    (:data:`GENERAL_T_END`)."""
    scene = scenes.get(name, **GENERAL_PARAMS.get(name, {}))
    model = scene.model
    T = min(scene.t_end, GENERAL_T_END.get(name, 3.0))
    kwargs: dict[str, Any] = dict(lam0=scene.lam0, method="DOP853", rtol=GENERAL_RTOL, atol=1e-2 * GENERAL_RTOL)
    kwargs["record"] = _grid(T)
    if "stabilize" in scene.params:
        kwargs["stabilize"] = scene.params["stabilize"]
    elif model.bounded:
        kwargs["stabilize"] = "baumgarte"
    start = time.perf_counter()
    run = simulate(model, scene.q0, scene.v0, T, backend=_registry_name(backend), **kwargs)
    return GeneralRun(run, (time.perf_counter() - start) * 1e3)


def _grid(T: float) -> np.ndarray:
    return np.linspace(0.0, T, 201)


def general_row(name: str, first: GeneralRun, second: GeneralRun | None) -> GeneralRow:
    """The row of scene ``name`` from its run on the first backend (and on the second, for the gap between them)."""
    scene = scenes.get(name, **GENERAL_PARAMS.get(name, {}))
    model, run = scene.model, first.trajectory
    T = float(run.t[-1]) if run.status == "failed" else min(scene.t_end, GENERAL_T_END.get(name, 3.0))
    gap = None if second is None else _on_grid_gap(run, second.trajectory, _grid(T))
    exact = None
    if scene.exact is not None:
        exact = max(float(np.abs(scene.exact(t)[0] - q).max()) for t, q in zip(run.t, run.q, strict=True))
    return GeneralRow(
        scene=name,
        what=_features(model, run),
        t_end=T,
        events=len(run.events),
        saturated=float(run.saturated.any(axis=1).mean()) if model.bounded else None,
        backend_gap=gap,
        residual=run.max_residual(),
        energy_balance=_largest_energy_balance(run),
        exact_error=exact,
        run_ms=first.run_ms,
    )


def general_rows(which: Backends) -> Iterator[GeneralRow]:
    """Every scene without a closed-form step (:func:`general_row`), here one after the other."""
    for name in scenes.names("general"):
        second = general_run(name, which.second) if which.second else None
        yield general_row(name, general_run(name, which.first), second)


#: The teaching pictures: file name → what draws it (each a task of its own).
FIGURES = ("two_masses.png", "realizability_map.png", "three_realizations.png", "skate.png")


def figure(out: Path, name: str) -> Path:
    """One teaching picture (:data:`FIGURES`) written into ``out``: rod vs servo, the realizability map, three
    realizations, the skate.

    Raises :class:`~gausspp.GaussppError` without matplotlib (an optional extra), before anything runs.
    """
    plt = plot.pyplot()
    out.mkdir(parents=True, exist_ok=True)
    draw = {
        "two_masses.png": two_masses_figure,
        "realizability_map.png": lambda: plot.realizability_map(realizability_grid()),
        "three_realizations.png": lambda: plot.three_realizations(
            runs=three_realizations_runs(), steady=suslov_steady()
        ),
        "skate.png": lambda: plot.skate(runs=skate_runs(), title=skate_title()),
    }[name]
    fig = draw()
    fig.savefig(out / name, dpi=100, bbox_inches="tight")
    plt.close(fig)
    return out / name


def figures(out: Path) -> list[Path]:
    """Every teaching picture (:func:`figure`), here one after the other."""
    return [figure(out, name) for name in FIGURES]


def two_masses_figure() -> Any:
    """Rod vs servo on the two-masses scene with a spring: both motions and their difference."""
    runs, params = {}, {}
    for realization in ("ideal", "servo"):
        scene = scenes.get("two-masses", realization=realization, k=3.0, v=0.5)
        params = scene.params
        runs[f"{'rod' if realization == 'ideal' else 'servo'}"] = simulate(
            scene.model, scene.q0, scene.v0, 4.0, method="rk4", lane="compiled", dt=1e-3, solver="direct", record=10
        )
    title = (
        f"scene two-masses: m1 = {params['m1']:g} kg, m2 = {params['m2']:g} kg, F = {params['F']:g} N on m2, "
        f"spring k = {params['k']:g} N/m, v0 = {params['v']:g} m/s\n"
        "kept by a rod (ideal, solid, circles) or a follower force on m1 (servo, dashed, squares); t in s, x in m"
    )
    return plot.trajectory(runs, difference=True, q_labels=["$x_1$", "$x_2$"], v_labels=["$v_1$", "$v_2$"], title=title)
