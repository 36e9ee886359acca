"""Redundant constraints: rank-deficient constraint Jacobians, on and slightly off the constraint manifold."""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np

from .. import qp, scenes
from ..constraints import Holonomic
from ..errors import GaussppError, RealizabilityError
from ..frontends import Lagrangian
from ..model import Model
from ..realizability import cosines
from ..results import StepResult
from ..simulate import simulate
from ._case import Case, fmt, quiet_c_output, realizability_warnings, recorded, relative, solvers

NAME = "redundant constraints"
WHAT = (
    "rank-deficient constraint Jacobians: a particle on a circle with the circle written twice (one step by the "
    "direct formula and every QP backend), and the pendulum's two pins plus the distance constraint they imply "
    "(dependent on the constraint manifold): direct and default QP along the manifold and at drifts δ = 1e-10…1e-2 "
    "off it; simulate from the manifold with and without projection, and from off it with projection"
)
EXPECTED = (
    "exact redundancy: a RealizabilityError naming the constraints and saying they are redundant, with every solver "
    "and backend; near-redundancy off the manifold: a RealizabilityWarning or a RealizabilityError, never a silent "
    "answer; every answer on the manifold, and every answer without a warning, is the minimal model's acceleration "
    "(≤ 1e-8); simulate fails with project errors only"
)

_PINS = ("pin-x", "pin-z", "distance")
_DRIFTS = (1e-10, 1e-8, 1e-6, 1e-4, 1e-3, 1e-2)


def circle_twice() -> tuple[Model, Model]:
    """A particle on the unit circle under gravity: the minimal model, and the circle written twice."""
    body = Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: 9.81 * q[1])
    circle = Holonomic(lambda q, t: ca.sumsqr(q) - 1.0, name="circle")
    twice = Holonomic(lambda q, t: 2.0 * (ca.sumsqr(q) - 1.0), name="circle again")
    return Model(body, [circle]), Model(body, [circle, twice])


def pendulum_with_distance() -> tuple[scenes.Scene, Model]:
    """The pendulum scene and the same body with its pins plus the distance constraint they imply."""
    scene = scenes.get("pendulum")
    L = float(scene.params["L"])
    distance = Holonomic(lambda q, t: q[0] ** 2 + q[1] ** 2 - L**2, name="distance")
    return scene, Model(scene.model.mechanism, [*scene.model.constraints, distance])


def pendulum_state(phi: float, omega: float, stretch: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``q = (cos φ·(1 + stretch), sin φ, φ)``, ``v = ω·(−sin φ, cos φ, 1)``: on the manifold iff ``stretch = 0``."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * (1.0 + stretch), s, phi]), np.array([-s * omega, c * omega, omega])


def _attempt(model: Model, q: np.ndarray, v: np.ndarray, solver: str, backend: str | None) -> tuple[Any, bool]:
    """One step at t = 0: (the result or the exception, whether a RealizabilityWarning came with it)."""
    with recorded() as caught, quiet_c_output():
        try:
            out: StepResult | Exception = model.step(0.0, q, v, solver=solver, backend=backend)
        except Exception as exc:  # noqa: BLE001 - judged by the caller; a non-project exception is a finding
            out = exc
    return out, bool(realizability_warnings(caught))


def _clear(out: Any, names: tuple[str, ...]) -> bool:
    """A RealizabilityError that names every constraint and says they are redundant."""
    return isinstance(out, RealizabilityError) and "redundant" in str(out) and all(repr(n) in str(out) for n in names)


def _kind(out: Any) -> str:
    return "answer" if isinstance(out, StepResult) else type(out).__name__


def case(quick: bool = True) -> Case:
    """Rank-deficient constraint Jacobians: what each solver and simulate do."""
    f: dict[str, float] = {}
    wrong_answers: list[str] = []
    non_project: list[str] = []

    def judge(out: Any, warned: bool, ref: np.ndarray, where: str, on_manifold: bool) -> None:
        if isinstance(out, StepResult):
            err = relative(out.a, ref)
            if err > 1e-8 and (on_manifold or not warned):
                wrong_answers.append(f"{where}: error {fmt(err)}, margin {out.margin:.2g}, warned: {warned}")
        elif not isinstance(out, GaussppError):
            non_project.append(f"{where}: {type(out).__name__}: {out}")

    # A. the same constraint written twice (exactly dependent rows), every solver and backend
    minimal, doubled = circle_twice()
    q = np.array([math.cos(0.3), math.sin(0.3)])
    v = 1.5 * np.array([-math.sin(0.3), math.cos(0.3)])
    ref = minimal.step(0.0, q, v, solver="direct").a
    data = doubled.step_data(0.0, q, v)
    duplicate_cosines = cosines(data.A, data.J, data.D)
    unclear_a: dict[str, str] = {}
    direct_message = ""
    ways = solvers(qp.names())
    for label, solver, backend in ways:
        out, warned = _attempt(doubled, q, v, solver, backend)
        judge(out, warned, ref, f"circle twice, {label}", True)
        if label == "direct":
            direct_message = str(out)
        if not _clear(out, ("circle", "circle again")):
            unclear_a[label] = "answer" if isinstance(out, StepResult) else f"{_kind(out)}: {out}"
    f.update(
        duplicate_solvers=float(len(ways)),
        duplicate_clear_errors=float(len(ways) - len(unclear_a)),
        duplicate_cosine_min=float(duplicate_cosines.min()),
        duplicate_cosine_max=float(duplicate_cosines.max()),
    )

    # B. pins + distance along the manifold: dependent rows, in floating point only nearly so
    scene, with_distance = pendulum_with_distance()
    grid = np.linspace(-3.0, 3.0, 61 if quick else 241)
    kinds_b: dict[str, int] = {}
    clear_b, max_err_b = 0, 0.0
    for phi in grid:
        q, v = pendulum_state(float(phi), 1.3)
        ref = scene.model.step(0.0, q, v, solver="direct").a
        for label, solver, backend in ways[:2]:
            out, warned = _attempt(with_distance, q, v, solver, backend)
            judge(out, warned, ref, f"pins + distance on the manifold at φ = {phi:.2f}, {label}", True)
            kinds_b[_kind(out)] = kinds_b.get(_kind(out), 0) + 1
            clear_b += _clear(out, _PINS)
            if isinstance(out, StepResult):
                max_err_b = max(max_err_b, relative(out.a, ref))
    steps_b = 2 * grid.size
    f.update(
        manifold_states=float(grid.size),
        manifold_steps=float(steps_b),
        manifold_clear_errors=float(clear_b),
        manifold_answers=float(kinds_b.get("answer", 0)),
        manifold_max_error=max_err_b,
    )

    # C. off the manifold by a drift δ: the rows are independent, S nearly singular
    phi0 = 0.7
    drifts = _DRIFTS if quick else tuple(10.0 ** np.arange(-12.0, -1.9, 0.5))
    outcomes_c: dict[str, list[float]] = {"error": [], "warned": [], "silent": []}
    answered: list[tuple[float, float, float]] = []  # (δ, margin, error vs the minimal model)
    for stretch in drifts:
        q, v = pendulum_state(phi0, 1.3, stretch)
        ref = scene.model.step(0.0, q, v, solver="direct").a
        for label, solver, backend in ways[:2]:
            out, warned = _attempt(with_distance, q, v, solver, backend)
            judge(out, warned, ref, f"pins + distance {stretch:.0e} off the manifold, {label}", False)
            if isinstance(out, StepResult):
                outcomes_c["warned" if warned else "silent"].append(stretch)
                answered.append((stretch, out.margin, relative(out.a, ref)))
                f[f"off_manifold_margin@{stretch:.0e}"] = out.margin
                f[f"off_manifold_error@{stretch:.0e}"] = relative(out.a, ref)
            else:
                outcomes_c["error"].append(stretch)
    c_fit = float(np.median([m / d**2 for d, m, _ in answered])) if answered else math.nan
    f.update(
        off_manifold_errors=float(len(outcomes_c["error"])),
        off_manifold_warned_answers=float(len(outcomes_c["warned"])),
        off_manifold_silent_answers=float(len(outcomes_c["silent"])),
        margin_over_drift_squared=c_fit,
        drift_at_margin_warn=math.sqrt(with_distance.margin_warn / c_fit) if c_fit > 0 else math.nan,
    )

    # D. simulate: from the (singular) manifold with and without projection, from off it with projection
    outcomes_d: dict[str, str] = {}
    off_q, off_v = pendulum_state(0.0, 0.0, 1e-3)
    runs = [
        ("rk4", None, scene.q0, scene.v0),
        ("rk4", "project", scene.q0, scene.v0),
        ("rk4-compiled", "project", scene.q0, scene.v0),
        ("DOP853", "project", scene.q0, scene.v0),
        ("rk4", "project", off_q, off_v),
    ]
    for method, stab, q0, v0 in runs:
        key = f"{method}{' + project' if stab else ''}{' from δ = 1e-3' if q0 is off_q else ''}"
        with recorded(), quiet_c_output():
            try:
                traj = simulate(with_distance, q0, v0, 1.0, dt=0.01, method=method, solver="direct", stabilize=stab)
                outcomes_d[key] = f"ran to t = {traj.t[-1]:g}"
            except GaussppError as exc:
                said = " (says redundant)" if "redundant" in str(exc) else ""
                outcomes_d[key] = f"{type(exc).__name__}{said}"
            except Exception as exc:  # noqa: BLE001 - a non-project exception is itself a finding
                outcomes_d[key] = f"{type(exc).__name__} (not a project error)"
                non_project.append(f"simulate {key}: {type(exc).__name__}: {exc}")
    f.update(
        simulate_runs=float(len(runs)),
        simulate_redundancy_named=float(sum("says redundant" in o for o in outcomes_d.values())),
        wrong_answers=float(len(wrong_answers)),
        non_project_exceptions=float(len(non_project)),
        unclear_manifold_outcomes=float(steps_b - clear_b - kinds_b.get("answer", 0)),
    )
    verdict = not unclear_a and not wrong_answers and not non_project and f["unclear_manifold_outcomes"] == 0

    def deltas(xs: list[float]) -> str:
        return f"δ = {min(xs):.0e}…{max(xs):.0e}" if xs else "none"

    observed = (
        f"Circle written twice: {len(ways) - len(unclear_a)}/{len(ways)} solvers raise a RealizabilityError naming "
        f"both constraints and saying they are redundant (direct: “{direct_message}”)"
        + ("; the others: " + "; ".join(f"{k}: {o.split(':')[0]}" for k, o in unclear_a.items()) if unclear_a else "")
        + f". realizability.cosines there: {fmt(f['duplicate_cosine_max'])}, {fmt(f['duplicate_cosine_min'])} (the "
        "smallest is the documented 0; for more than one constraint the values are singular values of a matrix of "
        f"cosines, and the largest exceeds 1). Pins + distance on the manifold ({grid.size} angles × direct/QP): "
        + ", ".join(f"{n} {k}" for k, n in kinds_b.items())
        + f", {clear_b} of them naming the three constraints and redundancy"
        + (f"; answers match the minimal model to {fmt(max_err_b)}" if kinds_b.get("answer") else "")
        + f". Off the manifold by δ (φ = {phi0}): RealizabilityError for {deltas(outcomes_c['error'])}, answers "
        f"with a RealizabilityWarning for {deltas(outcomes_c['warned'])}, silent answers for "
        f"{deltas(outcomes_c['silent'])}; the margin is ≈ {c_fit:.2g}·δ² (below margin_warn up to δ ≈ "
        f"{f['drift_at_margin_warn']:.2g}); the warned answers differ from the minimal model by "
        + (fmt(max(e for _, _, e in answered)) if answered else "–")
        + " — the three constraints are independent there and define another motion. simulate: "
        + "; ".join(f"{k}: {v}" for k, v in outcomes_d.items())
        + "."
    )
    problems = []
    if unclear_a:
        advice = [k for k, o in unclear_a.items() if "casadi:qrqp" in o]
        problems.append(
            "Exact redundancy through the qpsolvers route is not diagnosed as such: "
            + "; ".join(f"{k} raises {o}" for k, o in unclear_a.items())
            + " — no RealizabilityError, no constraint names, no margin (it is exactly 0), although direct, every "
            "casadi backend and qpsolvers:quadprog raise the clear RealizabilityError on the same step"
            + (
                f"; {', '.join(advice)} even advise backend='casadi:qrqp', which raises that RealizabilityError"
                if advice
                else ""
            )
            + ". The backend fails inside its solve, before the margin is looked at. Repro: `m = gp.Model(body, "
            "[circle, circle_again])` (gausspp.stability.redundant.circle_twice()); m.step(0, (cos 0.3, sin 0.3), "
            f"1.5·(−sin 0.3, cos 0.3), backend='{next(iter(unclear_a))}')."
        )
    if wrong_answers:
        problems.append(
            "An acceleration different from the minimal model's (on the manifold, or without a warning): "
            + "; ".join(wrong_answers[:3])
            + ". Repro: `sc, red = gausspp.stability.redundant.pendulum_with_distance()`; red.step(0, q, v) vs "
            "sc.model.step(0, q, v) at the state above (pendulum_state)."
        )
    if f["unclear_manifold_outcomes"]:
        problems.append(
            f"Redundant constraints on the manifold: {f['unclear_manifold_outcomes']:.0f} of {steps_b} steps end "
            f"neither in the clear RealizabilityError nor in the minimal model's answer ({kinds_b})."
        )
    if non_project:
        problems.append(
            "Non-project exceptions with redundant constraints: " + "; ".join(n[:160] for n in non_project[:3])
        )
    return Case(NAME, WHAT, EXPECTED, observed, bool(verdict), f, tuple(problems))
