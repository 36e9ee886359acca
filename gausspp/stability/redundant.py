"""Redundant constraints: rank-deficient constraint Jacobians, on and slightly off the constraint manifold.

Issue 7: ``solver='direct'`` needs independent rows and stops with a RealizabilityError naming the
constraints and their redundancy; ``solver='qp'`` hands a step whose rows are merely redundant to the
general Gauss QP (:mod:`gausspp.gauss_qp`), which returns the unique acceleration and the least-norm
multiplier, or a RealizabilityError when the dependent rows contradict each other.
"""

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
    "(dependent on the constraint manifold): direct and default QP along the manifold (every QP backend at a few "
    "angles) and at drifts δ = 1e-10…1e-2 off it, at φ = 0.7 (the rows become independent) and at φ = 0 (they "
    "stay exactly dependent, the right-hand sides become inconsistent); simulate with solver='direct' from the "
    "manifold with and without projection and from off it with projection, and once with solver='qp'"
)
EXPECTED = (
    "solver='direct': a RealizabilityError naming the constraints, saying they are redundant and pointing to "
    "solver='qp'; solver='qp' with every backend, where the rows are exactly dependent and consistent: the "
    "minimal model's acceleration (≤ 1e-10) and the least-norm multiplier (circle twice: λ_min·(1, 2)/5, equal to "
    "numpy's pinv solution; ≤ 1e-10); off the manifold by δ: an error, a RealizabilityWarning, or an answer within "
    "min(1e-7, 2δ) of the minimal model (the state's own drift) — never a silent wrong answer; dependent rows "
    "that contradict each other: a RealizabilityError; simulate with solver='direct' fails with project errors "
    "naming the redundancy"
)

_PINS = ("pin-x", "pin-z", "distance")
_CIRCLES = ("circle", "circle again")
_DRIFTS = (1e-10, 1e-8, 1e-6, 1e-4, 1e-3, 1e-2)
#: Acceleration and multiplier tolerance (relative) for exactly dependent, consistent rows.
EXACT_TOL = 1e-10
#: An answer without a warning at a state δ off the manifold may differ from the minimal model's by
#: ``min(SILENT_CAP, SILENT_PER_DRIFT·δ)`` (relative): no more than the state's own drift makes uncertain.
SILENT_CAP, SILENT_PER_DRIFT = 1e-7, 2.0
#: Largest relative difference of a simulated trajectory from the minimal model's.
SILENT_TOL = 1e-8
#: Drifts at the edge of the general QP's rank tolerance, scanned over the angles.
_EDGE_DRIFTS = (1e-8, 2e-8, 3e-8)
#: What solver='direct' adds to its error when the rows are redundant.
QP_ADVICE = "solver='qp' returns the unique acceleration and the least-norm multiplier"


def circle_twice() -> tuple[Model, Model]:
    """A particle on the unit circle under gravity: the minimal model, and the circle written twice."""
    body = Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: 9.81 * q[1])
    circle = Holonomic(lambda q, t: ca.sumsqr(q) - 1.0, name="circle")
    twice = Holonomic(lambda q, t: 2.0 * (ca.sumsqr(q) - 1.0), name="circle again")
    return Model(body, [circle]), Model(body, [circle, twice])


def circle_state() -> tuple[np.ndarray, np.ndarray]:
    """The circle's test state: ``q = (cos 0.3, sin 0.3)``, ``v = 1.5·(−sin 0.3, cos 0.3)`` (on the circle)."""
    return np.array([math.cos(0.3), math.sin(0.3)]), 1.5 * np.array([-math.sin(0.3), math.cos(0.3)])


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


def least_norm_multiplier(model: Model, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The least-norm ``u`` with ``D u = A a − f − r₀`` (numpy's pseudo-inverse, singular values < 1e-10·max cut)."""
    d = model.step_data(0.0, q, v)
    return np.linalg.pinv(d.D, rcond=1e-10) @ (d.A @ a - d.f - d.r0)


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


def _clear_direct(out: Any, names: tuple[str, ...]) -> bool:
    """The direct formula's error: clear (:func:`_clear`), and pointing to solver='qp'."""
    return _clear(out, names) and QP_ADVICE in str(out)


def _error_kind(out: Any, names: tuple[str, ...]) -> str:
    """``redundant`` (the clear error), ``contradict`` (inconsistent dependent rows), or ``other: …``."""
    if _clear(out, names):
        return "redundant"
    if isinstance(out, RealizabilityError) and "contradict each other" in str(out):
        return "contradict"
    return f"other: {type(out).__name__}: {out}"


def _kind(out: Any) -> str:
    return "answer" if isinstance(out, StepResult) else type(out).__name__


def case(quick: bool = True) -> Case:
    """Rank-deficient constraint Jacobians: what each solver and simulate do."""
    f: dict[str, float] = {}
    wrong_answers: list[str] = []
    non_project: list[str] = []

    def judge(out: Any, warned: bool, ref: np.ndarray, where: str, silent_tol: float | None = None) -> None:
        """Every answer is the minimal model's to EXACT_TOL; off the manifold (``silent_tol``), every unwarned one."""
        if isinstance(out, StepResult):
            err = relative(out.a, ref)
            if (silent_tol is None and err > EXACT_TOL) or (silent_tol is not None and err > silent_tol and not warned):
                wrong_answers.append(f"{where}: error {fmt(err)}, margin {out.margin:.2g}, warned: {warned}")
        elif not isinstance(out, GaussppError):
            non_project.append(f"{where}: {type(out).__name__}: {out}")

    # A. the same constraint written twice (exactly dependent rows), every solver and backend
    minimal, doubled = circle_twice()
    q, v = circle_state()
    ref_step = minimal.step(0.0, q, v, solver="direct")
    ref, lam_min = ref_step.a, float(ref_step.u[0])
    # D = [d, 2d] (d the minimal model's column): D u = d (u₁ + 2u₂) = d λ_min; least norm: u = λ_min (1, 2)/5
    derived = lam_min * np.array([1.0, 2.0]) / 5.0
    pinv_u = least_norm_multiplier(doubled, q, v, ref)
    data = doubled.step_data(0.0, q, v)
    duplicate_cosines = cosines(data.A, data.J, data.D)
    ways = solvers(qp.names())
    direct_out, _ = _attempt(doubled, q, v, "direct", None)
    judge(direct_out, False, ref, "circle twice, direct")
    bad_a: dict[str, str] = {}  # QP backend → what is wrong with its answer
    err_a = err_u = 0.0
    fallback_solvers: set[str] = set()
    warned_a = 0
    for label, solver, backend in ways[1:]:
        out, warned = _attempt(doubled, q, v, solver, backend)
        judge(out, warned, ref, f"circle twice, {label}")
        warned_a += warned
        if not isinstance(out, StepResult):
            bad_a[label] = f"{_kind(out)}: {out}"
            continue
        fallback_solvers.add(out.solver)
        ea, eu = relative(out.a, ref), relative(out.u, derived)
        err_a, err_u = max(err_a, ea), max(err_u, eu)
        if ea > EXACT_TOL or eu > EXACT_TOL or not out.solver.startswith("gauss-qp:"):
            bad_a[label] = f"answer by {out.solver}: acceleration {fmt(ea)}, multiplier {fmt(eu)} off"
    f.update(
        duplicate_solvers=float(len(ways)),
        duplicate_direct_clear_error=float(_clear_direct(direct_out, _CIRCLES)),
        duplicate_qp_backends=float(len(ways) - 1),
        duplicate_qp_right_answers=float(len(ways) - 1 - len(bad_a)),
        duplicate_qp_warned_answers=float(warned_a),
        duplicate_max_acceleration_error=err_a,
        duplicate_max_multiplier_error=err_u,
        duplicate_least_norm_vs_pinv=relative(derived, pinv_u),
        duplicate_minimal_multiplier=lam_min,
        duplicate_cosine_min=float(duplicate_cosines.min()),
        duplicate_cosine_max=float(duplicate_cosines.max()),
    )

    # B. pins + distance along the manifold: dependent rows, in floating point only nearly so
    scene, with_distance = pendulum_with_distance()
    default = ("qp", qp.get(None).name, None)
    grid = np.linspace(-3.0, 3.0, 61 if quick else 241)
    every_backend_at = set(grid[:: 20 if quick else 40].tolist())
    direct_clear_b, answers_b, default_answers_b, steps_b, backend_steps_b = 0, 0, 0, 0, 0
    max_err_b = max_u_b = 0.0
    unclear_b: list[str] = []
    failing_b: dict[str, list[float]] = {}  # QP backend → the angles (among every_backend_at) where it did not answer
    for phi in grid:
        q, v = pendulum_state(float(phi), 1.3)
        ref = scene.model.step(0.0, q, v, solver="direct").a
        out, warned = _attempt(with_distance, q, v, "direct", None)
        judge(out, warned, ref, f"pins + distance on the manifold at φ = {phi:.2f}, direct")
        direct_clear_b += _clear_direct(out, _PINS)
        if not _clear_direct(out, _PINS):
            unclear_b.append(f"φ = {phi:.2f}, direct: {_kind(out)}")
        backends = [None, *(b for _, _, b in ways[1:])] if phi in every_backend_at else [None]
        for backend in backends:
            out, warned = _attempt(with_distance, q, v, "qp", backend)
            label = qp.get(backend).name
            judge(out, warned, ref, f"pins + distance on the manifold at φ = {phi:.2f}, {label}")
            steps_b += 1
            backend_steps_b += backend is not None
            if isinstance(out, StepResult):
                answers_b += 1
                default_answers_b += backend is None
                max_err_b = max(max_err_b, relative(out.a, ref))
                max_u_b = max(max_u_b, relative(out.u, least_norm_multiplier(with_distance, q, v, ref)))
            elif not _clear(out, _PINS):
                unclear_b.append(f"φ = {phi:.2f}, {label}: {_kind(out)}: {out}")
                failing_b.setdefault(label, []).append(float(phi))
    f.update(
        manifold_states=float(grid.size),
        manifold_direct_clear_errors=float(direct_clear_b),
        manifold_qp_steps=float(steps_b),
        manifold_qp_backend_steps=float(backend_steps_b),
        manifold_qp_answers=float(answers_b),
        manifold_default_qp_answers=float(default_answers_b),
        manifold_max_error=max_err_b,
        manifold_max_multiplier_error=max_u_b,
        unclear_manifold_outcomes=float(len(unclear_b)),
    )

    # C. off the manifold by a drift δ. At φ = 0.7 the rows become independent (S nearly singular, margin ∝ δ²);
    # at φ = 0 the distance row stays parallel to pin-x's and its right-hand side becomes inconsistent.
    drifts = _DRIFTS if quick else tuple(float(d) for d in 10.0 ** np.arange(-12.0, -1.9, 0.5))
    outcomes_c: dict[str, dict[str, list[float]]] = {}  # "φ, solver" → outcome → drifts
    answered: list[tuple[float, float, float]] = []  # (δ, margin, error vs the minimal model), φ = 0.7, warned
    silent_ratio = silent_max = silent_drift = 0.0  # an unwarned answer's largest error/δ, error, and δ
    misdiagnosed: list[str] = []  # errors neither the clear one nor "contradict each other"
    for phi0 in (0.7, 0.0):
        for stretch in drifts:
            q, v = pendulum_state(phi0, 1.3, stretch)
            ref = scene.model.step(0.0, q, v, solver="direct").a
            for solver, label, backend in (("direct", "direct", None), default):
                out, warned = _attempt(with_distance, q, v, solver, backend)
                where = f"pins + distance {stretch:.0e} off the manifold at φ = {phi0}, {label}"
                judge(out, warned, ref, where, min(SILENT_CAP, SILENT_PER_DRIFT * stretch))
                if isinstance(out, StepResult):
                    err = relative(out.a, ref)
                    outcome = f"warned answer ({out.solver})" if warned else f"silent answer ({out.solver})"
                    if warned and phi0 == 0.7:
                        answered.append((stretch, out.margin, err))
                    if not warned:
                        silent_ratio, silent_max = max(silent_ratio, float(err / stretch)), max(silent_max, err)
                        silent_drift = max(silent_drift, stretch)
                    f[f"off_manifold_error@{phi0}/{label}/{stretch:.0e}"] = err
                    f[f"off_manifold_margin@{phi0}/{label}/{stretch:.0e}"] = out.margin
                else:
                    outcome = _error_kind(out, _PINS)
                    if outcome.startswith("other"):
                        misdiagnosed.append(f"δ = {stretch:.0e}, φ = {phi0}, {label}: {outcome[7:]}")
                        outcome = "other error"
                outcomes_c.setdefault(f"φ = {phi0}, {label}", {}).setdefault(outcome, []).append(stretch)
    # the edge of the silent window (where the general QP's rank tolerance still deems the rows dependent), all angles
    edge_grid = grid[:: 5 if quick else 1]
    edge: dict[str, int] = {}
    for phi in edge_grid:
        for stretch in _EDGE_DRIFTS:
            q, v = pendulum_state(float(phi), 1.3, stretch)
            ref = scene.model.step(0.0, q, v, solver="direct").a
            out, warned = _attempt(with_distance, q, v, "qp", None)
            where = f"pins + distance {stretch:.0e} off the manifold at φ = {phi:.2f}, {default[1]}"
            judge(out, warned, ref, where, min(SILENT_CAP, SILENT_PER_DRIFT * stretch))
            if isinstance(out, StepResult):
                outcome = "warned answer" if warned else "silent answer"
                if not warned:
                    err = relative(out.a, ref)
                    silent_ratio, silent_max = max(silent_ratio, float(err / stretch)), max(silent_max, err)
                    silent_drift = max(silent_drift, stretch)
            else:
                outcome = _error_kind(out, _PINS)
                if outcome.startswith("other"):
                    outcome = "other error"
            edge[outcome] = edge.get(outcome, 0) + 1
    counts = {o: sum(len(d.get(o, [])) for d in outcomes_c.values()) for o in ("redundant", "contradict")}
    c_fit = float(np.median([m / d**2 for d, m, _ in answered])) if answered else math.nan
    f.update(
        off_manifold_steps=float(2 * 2 * len(drifts)),
        off_manifold_redundant_errors=float(counts["redundant"]),
        off_manifold_contradiction_errors=float(counts["contradict"]),
        off_manifold_other_errors=float(len(misdiagnosed)),
        off_manifold_warned_answers=float(sum(len(d[o]) for d in outcomes_c.values() for o in d if "warned" in o)),
        off_manifold_silent_answers=float(sum(len(d[o]) for d in outcomes_c.values() for o in d if "silent" in o)),
        off_manifold_silent_error_over_drift=silent_ratio,
        off_manifold_silent_max_error=silent_max,
        off_manifold_silent_max_drift=silent_drift,
        edge_steps=float(edge_grid.size * len(_EDGE_DRIFTS)),
        edge_silent_answers=float(edge.get("silent answer", 0)),
        edge_other_errors=float(edge.get("other error", 0)),
        off_manifold_warned_max_error=max((e for _, _, e in answered), default=math.nan),
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
    lanes = [(*run, "direct") for run in runs] + [("rk4", None, scene.q0, scene.v0, "qp")]  # qp: recorded only
    for method, stab, q0, v0, solver in lanes:
        key = f"{method}{' + project' if stab else ''}{' from δ = 1e-3' if q0 is off_q else ''}, {solver}"
        with recorded(), quiet_c_output():
            try:
                traj = simulate(with_distance, q0, v0, 1.0, dt=0.01, method=method, solver=solver, stabilize=stab)
                ref_traj = simulate(scene.model, q0, v0, 1.0, dt=0.01, method=method, solver=solver, stabilize=stab)
                err = relative(traj.q, ref_traj.q) if traj.q.shape == ref_traj.q.shape else math.inf
                outcomes_d[key] = f"ran to t = {traj.t[-1]:g}, q within {fmt(err)} of the minimal model"
                if err > SILENT_TOL:
                    wrong_answers.append(f"simulate {key}: q differs from the minimal model by {fmt(err)}")
            except GaussppError as exc:
                said = " (says redundant)" if "redundant" in str(exc) else ""
                outcomes_d[key] = f"{type(exc).__name__}{said}"
            except Exception as exc:  # noqa: BLE001 - a non-project exception is itself a finding
                outcomes_d[key] = f"{type(exc).__name__} (not a project error)"
                non_project.append(f"simulate {key}: {type(exc).__name__}: {exc}")
    f.update(
        simulate_runs=float(len(runs)),
        simulate_redundancy_named=float(sum("says redundant" in o for k, o in outcomes_d.items() if "direct" in k)),
        simulate_qp_redundancy_named=float(sum("says redundant" in o for k, o in outcomes_d.items() if "qp" in k)),
        wrong_answers=float(len(wrong_answers)),
        non_project_exceptions=float(len(non_project)),
    )
    verdict = (
        f["duplicate_direct_clear_error"] == 1
        and not bad_a
        and f["duplicate_least_norm_vs_pinv"] <= EXACT_TOL
        and not unclear_b
        and max_u_b <= EXACT_TOL
        and not wrong_answers
        and not non_project
        and f["simulate_redundancy_named"] == len(runs)
    )

    def deltas(xs: list[float]) -> str:
        if not xs:
            return "none"
        return f"δ = {xs[0]:.0e}" if min(xs) == max(xs) else f"δ = {min(xs):.0e}…{max(xs):.0e}"

    observed = (
        "Circle written twice: direct raises "
        + ("the clear RealizabilityError" if f["duplicate_direct_clear_error"] else "something else")
        + f" (“{direct_out}”); {len(ways) - 1 - len(bad_a)}/{len(ways) - 1} QP backends answer through "
        + ", ".join(sorted(fallback_solvers))
        + f" with the minimal model's acceleration (worst {fmt(err_a)}) and the least-norm multiplier "
        f"λ_min·(1, 2)/5 = ({derived[0]:.6g}, {derived[1]:.6g}) (λ_min = {lam_min:.6g}; worst {fmt(err_u)}; numpy's "
        f"pinv solution differs by {fmt(f['duplicate_least_norm_vs_pinv'])}), {warned_a} with a RealizabilityWarning"
        + ("; wrong: " + "; ".join(f"{k}: {o}" for k, o in bad_a.items()) if bad_a else "")
        + f". realizability.cosines there: {fmt(f['duplicate_cosine_max'])}, {fmt(f['duplicate_cosine_min'])} (the "
        "smallest is the documented 0; for more than one constraint the values are singular values of a matrix of "
        f"cosines, and the largest exceeds 1). Pins + distance on the manifold ({grid.size} angles): direct raises "
        f"the clear error at {direct_clear_b}; the QP ({steps_b} steps, {backend_steps_b} of them every backend at "
        f"{len(every_backend_at)} angles) answers {answers_b} times ({default_answers_b}/{grid.size} with the "
        f"default backend), acceleration within {fmt(max_err_b)} of the "
        f"minimal model, multiplier within {fmt(max_u_b)} of the least-norm one"
        + (f"; not so: {'; '.join(unclear_b[:3])}" if unclear_b else "")
        + ". Off the manifold by δ: "
        + "; ".join(f"{k}: " + ", ".join(f"{o} for {deltas(xs)}" for o, xs in d.items()) for k, d in outcomes_c.items())
        + f" (“redundant”: the clear error; “contradict”: the general QP's inconsistency error). Silent answers "
        f"differ from the minimal model by ≤ {fmt(silent_ratio)}·δ (at most {fmt(silent_max)}, at δ ≤ "
        f"{silent_drift:.0e}; over {edge_grid.size} angles at δ = {', '.join(f'{d:.0e}' for d in _EDGE_DRIFTS)}: "
        + ", ".join(f"{n} {k}" for k, n in sorted(edge.items()))
        + f"); at φ = 0.7 the margin is ≈ {c_fit:.2g}·δ² (below "
        f"margin_warn up to δ ≈ {f['drift_at_margin_warn']:.2g}) and the warned answers differ from the minimal "
        f"model by {fmt(f['off_manifold_warned_max_error'])} — the three constraints are independent there and "
        "define another motion. simulate: " + "; ".join(f"{k}: {v}" for k, v in outcomes_d.items()) + "."
    )
    problems = []
    if misdiagnosed:
        problems.append(
            "Nearly dependent ideal constraints off the manifold: the QP's fallback to the general Gauss QP "
            "replaces the compiled step's clear error (margin ≈ 0, “remove a redundant constraint”) by a "
            "misleading one: "
            + "; ".join(m[:360] for m in misdiagnosed[:2])
            + f" ({len(misdiagnosed)} of {2 * len(drifts)} default-QP steps off the manifold at φ = 0.7 and 0; "
            f"{edge.get('other error', 0)} of {edge_grid.size * len(_EDGE_DRIFTS)} in the scan of the angles at "
            "δ = 1e-8…3e-8). The realizations are "
            "ideal (D = Jᵀ, so rank J A⁻¹ D = rank J exactly); gauss_qp.solve_general compares the numerical ranks "
            "of J and of S = J A⁻¹ D with the same relative tolerance (RANK_TOL = 1e-9), but S's singular values are "
            "those of J squared: at φ = 0.7 J's smallest relative singular value ≈ 0.05·δ counts from δ ≈ 2e-8 on, "
            "S's ≈ 2e-3·δ² not before δ ≈ 7e-4, so 'rank S < rank J' fires at every δ ≈ 2e-8…1e-5 that the compiled "
            "step hands over (margin below margin_error). "
            "Right: the compiled step's RealizabilityError (naming the redundancy), e.g. re-raise it in "
            "Model._redundant_step when the general QP fails. Repro: sc, m = gausspp.stability.redundant."
            "pendulum_with_distance(); q, v = gausspp.stability.redundant.pendulum_state(0.7, 1.3, 1e-6); "
            "m.step(0, q, v)."
        )
    bad_backends = sorted(set(bad_a) | set(failing_b))
    if bad_backends:
        problems.append(
            "Exactly dependent, consistent rows with solver='qp': not every backend returns the minimal model's "
            "acceleration with the least-norm multiplier — "
            + "; ".join(
                f"{b}: circle twice: {bad_a.get(b, 'right')[:160]}; pins + distance on the manifold: no answer at "
                f"{len(failing_b.get(b, []))}/{len(every_backend_at)} angles"
                + (f" (φ = {', '.join(f'{x:.1f}' for x in failing_b[b])})" if b in failing_b else "")
                for b in bad_backends
            )
            + ". The general QP's compulsion stage minimizes ‖W u‖² with W = R⁻ᵀD, whose columns are dependent "
            "when the rows are redundant: its Hessian WᵀW is singular (only positive semidefinite), which quadprog "
            "refuses ('matrix P is not positive definite') or, when round-off makes it barely definite, accepts — "
            "answer or failure is decided by round-off. Right: the answer (e.g. solve the compulsion stage in the "
            "reduced variables VᵀW u, or add the least-norm term, for backends that need P ≻ 0). Repro: "
            "`_, m = gausspp.stability.redundant.circle_twice()`; q, v = gausspp.stability.redundant.circle_state(); "
            f"m.step(0, q, v, backend='{bad_backends[0]}')."
        )
    if f["duplicate_direct_clear_error"] != 1:
        problems.append(f"Circle written twice, solver='direct': not the clear RealizabilityError: {direct_out!r}")
    if wrong_answers:
        problems.append(
            "An acceleration different from the minimal model's (on the manifold, or without a warning): "
            + "; ".join(wrong_answers[:3])
            + ". Repro: `sc, red = gausspp.stability.redundant.pendulum_with_distance()`; red.step(0, q, v) vs "
            "sc.model.step(0, q, v) at the state above (pendulum_state)."
        )
    others_b = [u for u in unclear_b if not any(f", {b}:" in u for b in failing_b)]
    if others_b or max_u_b > EXACT_TOL:
        problems.append(
            f"Redundant constraints on the manifold: {len(others_b)} steps end neither in the clear error (direct) "
            f"nor in the minimal model's answer (QP), worst multiplier {fmt(max_u_b)} off the least-norm one: "
            + "; ".join(others_b[:3])
        )
    if f["simulate_redundancy_named"] != len(runs):
        problems.append("simulate with solver='direct' and redundant constraints: " + str(outcomes_d))
    if non_project:
        problems.append(
            "Non-project exceptions with redundant constraints: " + "; ".join(n[:160] for n in non_project[:3])
        )
    return Case(NAME, WHAT, EXPECTED, observed, bool(verdict), f, tuple(problems))
