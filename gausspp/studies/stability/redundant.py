"""Redundant constraints: rank-deficient constraint Jacobians, on and off the constraint manifold.

``solver='direct'`` needs independent rows and stops with a RealizabilityError saying the rows are
redundant and pointing to ``solver='qp'``. ``solver='qp'`` decides which rows are redundant at the
nearest state on the constraint manifold (:mod:`gausspp.step.general.redundancy`: rows kept in
declared order) and solves the step at the actual state with the kept rows — the minimal model's
rows. So every QP backend returns the minimal model's acceleration, on the manifold (with the
least-norm multiplier) and off it (the rows there are independent by the drift only), and a
RealizabilityError ("contradict each other") when the dependent rows describe different constraints.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...errors import GaussppError, RealizabilityError
from ...simulation.simulate import simulate
from ...step import qp
from ...step.realizability import cosines
from ...step.results import StepResult
from .common import Case, fmt, quiet_c_output, recorded, relative
from .redundant_off_manifold import off_manifold_section
from .redundant_setups import (
    CIRCLES,
    EXACT_TOL,
    OFF_FLOOR,
    OFF_PER_DRIFT,
    PINS,
    QP_ADVICE,
    SIMULATE_TOL,
    Findings,
    Section,
    attempt,
    circle_state,
    circle_twice,
    clear_direct,
    contradicting_models,
    kind,
    least_norm_multiplier,
    off_tol,
    pendulum_state,
    pendulum_with_distance,
    qp_ways,
    two_masses,
)

__all__ = [
    "off_tol",
    "EXACT_TOL",
    "EXPECTED",
    "NAME",
    "OFF_FLOOR",
    "OFF_PER_DRIFT",
    "QP_ADVICE",
    "SIMULATE_TOL",
    "WHAT",
    "case",
    "circle_state",
    "circle_twice",
    "contradicting_models",
    "least_norm_multiplier",
    "pendulum_state",
    "pendulum_with_distance",
    "two_masses",
]

NAME = "redundant constraints"
WHAT = (
    "rank-deficient constraint Jacobians: a particle on a circle with the circle written twice (one step by the "
    "direct formula and every QP backend); the pendulum's two pins plus the distance constraint they imply "
    "(dependent on the constraint manifold): along the manifold (the default QP at every angle, every backend at "
    "a few), and off it by drifts δ = 1e-10…1e-2 at φ = 0.7 (the rows become independent) and φ = 0 (they stay "
    "dependent) and by δ = 1e-8…3e-8 over the angles, every QP backend and the direct formula; dependent rows "
    "that contradict each other (two velocity constraints with the same row and different right-hand sides, two "
    "positions x = 0 and x = 0.5); simulate with solver='direct' and with solver='qp' (rk4 with and without "
    "projection, DOP853, and from off the manifold with projection)"
)
EXPECTED = (
    "solver='direct': a RealizabilityError naming the constraints, saying they are redundant and pointing to "
    "solver='qp'; solver='qp' with every backend: the minimal model's acceleration — on the manifold to 1e-10 with "
    "the least-norm multiplier (circle twice: λ_min·(1, 2)/5, numpy's pinv solution), off it by δ to "
    "1e-12 + 2δ (the minimal model's rows, at the same state) — never an error and never another motion; dependent "
    "rows that contradict each other: a RealizabilityError; simulate: solver='direct' fails naming the "
    "redundancy, solver='qp' follows the minimal model's run"
)


def _duplicate_answers(
    found: Findings, doubled: Any, q: np.ndarray, v: np.ndarray, ref: np.ndarray, derived: np.ndarray
) -> tuple[dict[str, str], float, float, set[str], int]:
    """Every QP backend on the circle written twice: what is wrong per backend, the worst acceleration and
    multiplier errors, the routes that answered, and how many answers came with a RealizabilityWarning."""
    bad: dict[str, str] = {}  # QP backend → what is wrong with its answer
    err_a = err_u = 0.0
    routes: set[str] = set()
    warned_a = 0
    for label, solver, backend in qp_ways():
        out, warned = attempt(doubled, q, v, solver, backend)
        found.judge(out, ref, EXACT_TOL, f"circle twice, {label}")
        warned_a += warned
        if not isinstance(out, StepResult):
            bad[label] = f"{kind(out)}: {out}"
            continue
        routes.add(out.solver)
        ea, eu = relative(out.a, ref), relative(out.u, derived)
        err_a, err_u = max(err_a, ea), max(err_u, eu)
        if ea > EXACT_TOL or eu > EXACT_TOL or not out.solver.startswith("gauss-qp:"):
            bad[label] = f"answer by {out.solver}: acceleration {fmt(ea)}, multiplier {fmt(eu)} off"
    return bad, err_a, err_u, routes, warned_a


def _duplicates(found: Findings) -> Section:
    """A. The circle written twice (exactly dependent rows, everywhere): the direct formula and every QP backend."""
    minimal, doubled = circle_twice()
    q, v = circle_state()
    ref_step = minimal.step(0.0, q, v, solver="direct")
    ref, lam_min = ref_step.a, float(ref_step.u[0])
    # D = [d, 2d] (d the minimal model's column): D u = d (u₁ + 2u₂) = d λ_min; least norm: u = λ_min (1, 2)/5
    derived = lam_min * np.array([1.0, 2.0]) / 5.0
    data = doubled.step_data(0.0, q, v)
    duplicate_cosines = cosines(data.A, data.J, data.D)
    ways = qp_ways()
    direct_out, _ = attempt(doubled, q, v, "direct", None)
    found.judge(direct_out, ref, EXACT_TOL, "circle twice, direct")
    bad, err_a, err_u, routes, warned_a = _duplicate_answers(found, doubled, q, v, ref, derived)
    clear = clear_direct(direct_out, CIRCLES)
    f = dict(
        duplicate_solvers=float(len(ways) + 1),
        duplicate_direct_clear_error=float(clear),
        duplicate_qp_backends=float(len(ways)),
        duplicate_qp_right_answers=float(len(ways) - len(bad)),
        duplicate_qp_warned_answers=float(warned_a),
        duplicate_max_acceleration_error=err_a,
        duplicate_max_multiplier_error=err_u,
        duplicate_least_norm_vs_pinv=relative(derived, least_norm_multiplier(doubled, q, v, ref)),
        duplicate_minimal_multiplier=lam_min,
        duplicate_cosine_min=float(duplicate_cosines.min()),
        duplicate_cosine_max=float(duplicate_cosines.max()),
    )
    observed = (
        "Circle written twice: direct raises "
        + ("the clear RealizabilityError" if clear else "something else")
        + f" (“{direct_out}”); {len(ways) - len(bad)}/{len(ways)} QP backends answer through "
        + ", ".join(sorted(routes))
        + f" with the minimal model's acceleration (worst {fmt(err_a)}) and the least-norm multiplier "
        f"λ_min·(1, 2)/5 = ({derived[0]:.6g}, {derived[1]:.6g}) (λ_min = {lam_min:.6g}; worst {fmt(err_u)}; numpy's "
        f"pinv solution differs by {fmt(f['duplicate_least_norm_vs_pinv'])}), {warned_a} with a RealizabilityWarning"
        + ("; wrong: " + "; ".join(f"{k}: {o}" for k, o in bad.items()) if bad else "")
        + f". realizability.cosines there: {fmt(f['duplicate_cosine_max'])}, {fmt(f['duplicate_cosine_min'])} (the "
        "smallest is the documented 0; for more than one constraint the values are singular values of a matrix of "
        "cosines, and the largest exceeds 1)."
    )
    problems = []
    if not clear:
        problems.append(f"Circle written twice, solver='direct': not the clear RealizabilityError: {direct_out!r}")
    if bad:
        problems.append(
            "Exactly dependent, consistent rows with solver='qp': not every backend returns the minimal model's "
            "acceleration with the least-norm multiplier — "
            + "; ".join(f"{b}: {o[:200]}" for b, o in bad.items())
            + ". Repro: `_, m = gausspp.studies.stability.redundant.circle_twice()`; q, v = "
            f"gausspp.studies.stability.redundant.circle_state(); m.step(0, q, v, backend='{next(iter(bad))}')."
        )
    return Section(f, observed, problems)


def _on_manifold(found: Findings, quick: bool) -> Section:
    """B. Pins + distance along the manifold: dependent rows, in floating point only nearly so."""
    scene, with_distance = pendulum_with_distance()
    grid = np.linspace(-3.0, 3.0, 61 if quick else 241)
    every_backend_at = set(grid[:: 20 if quick else 40].tolist())
    backends = [None, *(b for _, _, b in qp_ways())]
    direct_clear = answers = default_answers = steps = backend_steps = 0
    max_err = max_u = 0.0
    unclear: list[str] = []
    for phi in grid:
        q, v = pendulum_state(float(phi), 1.3)
        ref = scene.model.step(0.0, q, v, solver="direct").a
        out, _ = attempt(with_distance, q, v, "direct", None)
        found.judge(out, ref, EXACT_TOL, f"pins + distance on the manifold at φ = {phi:.2f}, direct")
        direct_clear += clear_direct(out, PINS)
        if not clear_direct(out, PINS):
            unclear.append(f"φ = {phi:.2f}, direct: {kind(out)}: {out}")
        for backend in backends if phi in every_backend_at else [None]:
            out, _ = attempt(with_distance, q, v, "qp", backend)
            label = qp.get(backend).name
            found.judge(out, ref, EXACT_TOL, f"pins + distance on the manifold at φ = {phi:.2f}, {label}")
            steps += 1
            backend_steps += backend is not None
            if isinstance(out, StepResult):
                answers += 1
                default_answers += backend is None
                max_err = max(max_err, relative(out.a, ref))
                max_u = max(max_u, relative(out.u, least_norm_multiplier(with_distance, q, v, ref)))
            else:
                unclear.append(f"φ = {phi:.2f}, {label}: {kind(out)}: {out}")
    f = dict(
        manifold_states=float(grid.size),
        manifold_direct_clear_errors=float(direct_clear),
        manifold_qp_steps=float(steps),
        manifold_qp_backend_steps=float(backend_steps),
        manifold_qp_answers=float(answers),
        manifold_default_qp_answers=float(default_answers),
        manifold_max_error=max_err,
        manifold_max_multiplier_error=max_u,
        unclear_manifold_outcomes=float(len(unclear)),
    )
    observed = (
        f"Pins + distance on the manifold ({grid.size} angles): direct raises the clear error at {direct_clear}; "
        f"the QP ({steps} steps, {backend_steps} of them every backend at {len(every_backend_at)} angles) answers "
        f"{answers} times ({default_answers}/{grid.size} with the default backend), acceleration within "
        f"{fmt(max_err)} of the minimal model, multiplier within {fmt(max_u)} of the least-norm one"
        + (f"; not so: {'; '.join(unclear[:3])}" if unclear else "")
        + "."
    )
    problems = []
    if unclear or max_u > EXACT_TOL:
        problems.append(
            f"Redundant constraints on the manifold: {len(unclear)} steps end neither in the clear error (direct) "
            f"nor in the minimal model's answer (QP), worst multiplier {fmt(max_u)} off the least-norm one: "
            + "; ".join(u[:300] for u in unclear[:3])
        )
    return Section(f, observed, problems)


def _contradictions(found: Findings) -> Section:
    """D. Dependent rows that contradict each other: the direct formula and every QP backend must raise."""
    ways = [("direct", "direct", None), *qp_ways()]
    answered: list[str] = []
    raised = 0
    for name, (model, q, v, t) in contradicting_models().items():
        for label, solver, backend in ways:
            out, _ = attempt(model, q, v, solver, backend, t)
            if isinstance(out, RealizabilityError):
                raised += 1
            elif isinstance(out, StepResult):
                answered.append(f"{name}, {label}: a = {np.array2string(out.a, precision=3)}")
            elif not isinstance(out, GaussppError):
                found.non_project.append(f"{name}, {label}: {type(out).__name__}: {out}")
            else:
                answered.append(f"{name}, {label}: {type(out).__name__}: {str(out)[:160]}")
    steps = len(contradicting_models()) * len(ways)
    f = dict(contradiction_steps=float(steps), contradiction_realizability_errors=float(raised))
    observed = f"Dependent rows that contradict each other: a RealizabilityError in {raised}/{steps} steps" + (
        f"; not so: {'; '.join(answered[:4])}" if answered else ""
    )
    problems = []
    if answered:
        problems.append(
            f"Dependent rows that contradict each other: {len(answered)}/{steps} steps do not raise a "
            "RealizabilityError — " + "; ".join(answered[:3]) + ". Holonomic rows x₀ = 0 and x₀ = 0.5 have the same "
            "velocity and acceleration rows; only their positions disagree, and the reference state on the "
            "manifold (where that is checked) is looked for only when the rows are ambiguous at the state itself "
            "(gauss_qp.solve_general). Repro: m = gausspp.studies.stability.redundant.contradicting_models()"
            "['positions at x = 0.25'][0]; m.step(0, [0.25, 0], [0, 0])."
        )
    return Section(f, observed + ".", problems)


def _simulations(found: Findings) -> Section:
    """E. simulate: solver='direct' must fail naming the redundancy; solver='qp' must follow the minimal model.

    ``rk4`` in the compiled lane runs the compiled step, which has no general QP: with solver='qp' it must refuse,
    naming the redundancy. DOP853 is compared at 11 recorded times (its accepted steps may differ).
    """
    scene, with_distance = pendulum_with_distance()
    off_q, off_v = pendulum_state(0.0, 0.0, 1e-3)
    runs = [
        ("rk4", None, scene.q0, scene.v0),
        ("rk4", "project", scene.q0, scene.v0),
        ("rk4 compiled", "project", scene.q0, scene.v0),
        ("DOP853", "project", scene.q0, scene.v0),
        ("rk4", "project", off_q, off_v),
    ]
    outcomes: dict[str, str] = {}
    named = followed = compiled_refused = 0
    for solver in ("direct", "qp"):
        for method, stab, q0, v0 in runs:
            key = f"{method}{' + project' if stab else ''}{' from δ = 1e-3' if q0 is off_q else ''}, {solver}"
            lane = "compiled" if method.endswith("compiled") else None
            options: dict[str, Any] = dict(dt=0.01, method=method.split()[0], lane=lane, solver=solver, stabilize=stab)
            if method == "DOP853":
                options["record"] = np.linspace(0.0, 1.0, 11)
            with recorded(), quiet_c_output():
                try:
                    traj = simulate(with_distance, q0, v0, 1.0, **options)
                    ref = simulate(scene.model, q0, v0, 1.0, **{**options, "solver": "direct"})
                    err = relative(traj.q, ref.q) if traj.q.shape == ref.q.shape else math.inf
                    outcomes[key] = f"ran to t = {traj.t[-1]:g}, q within {fmt(err)} of the minimal model"
                    if solver == "direct" or err > SIMULATE_TOL:
                        found.wrong_answers.append(f"simulate {key}: {outcomes[key]}")
                    followed += solver == "qp" and err <= SIMULATE_TOL
                except GaussppError as exc:
                    says = "redundant" in str(exc)
                    outcomes[key] = f"{type(exc).__name__}{' (says redundant)' if says else ''}: {str(exc)[:200]}"
                    named += solver == "direct" and says
                    # the compiled integrator has no general QP: its refusal naming the redundancy is right
                    compiled_refused += solver == "qp" and method == "rk4 compiled" and says
                except Exception as exc:  # noqa: BLE001 - a non-project exception is itself a finding
                    outcomes[key] = f"{type(exc).__name__} (not a project error)"
                    found.non_project.append(f"simulate {key}: {type(exc).__name__}: {exc}")
    qp_runs = len(runs) - compiled_refused
    f = dict(
        simulate_runs=float(len(runs)),
        simulate_redundancy_named=float(named),
        simulate_qp_runs=float(qp_runs),
        simulate_qp_followed_minimal=float(followed),
        simulate_compiled_qp_refusals=float(compiled_refused),
    )
    observed = "simulate: " + "; ".join(f"{k}: {v}" for k, v in outcomes.items()) + "."
    problems = []
    if named != len(runs):
        problems.append("simulate with solver='direct' and redundant constraints: " + str(outcomes))
    if followed != qp_runs or compiled_refused != 1:
        problems.append(
            "simulate with solver='qp' and redundant constraints does not follow the minimal model: "
            + "; ".join(f"{k}: {v}" for k, v in outcomes.items() if k.endswith("qp"))
        )
    return Section(f, observed, problems)


def case(quick: bool = True) -> Case:
    """Rank-deficient constraint Jacobians: what each solver and simulate do."""
    found = Findings()
    sections = [
        _duplicates(found),
        _on_manifold(found, quick),
        off_manifold_section(found, quick),
        _contradictions(found),
        _simulations(found),
    ]
    f: dict[str, float] = {}
    for section in sections:
        f.update(section.figures)
    f.update(wrong_answers=float(len(found.wrong_answers)), non_project_exceptions=float(len(found.non_project)))
    problems = [p for section in sections for p in section.problems]
    if found.wrong_answers:
        problems.append(
            "An acceleration (or run) different from the minimal model's: "
            + "; ".join(w[:300] for w in found.wrong_answers[:3])
            + ". Repro: `sc, red = gausspp.studies.stability.redundant.pendulum_with_distance()`; red.step(0, q, v) vs "
            "sc.model.step(0, q, v, solver='direct') at the state above (pendulum_state)."
        )
    if found.non_project:
        problems.append(
            "Non-project exceptions with redundant constraints: " + "; ".join(n[:160] for n in found.non_project[:3])
        )
    observed = " ".join(section.observed for section in sections)
    return Case(NAME, WHAT, EXPECTED, observed, not problems, f, tuple(problems))
