"""Realizability margins 1e-3…1e-9 on the crane: warnings, errors, and the error's growth against the margin."""

from __future__ import annotations

import math

import numpy as np

from ... import scenes
from ...errors import GaussppError, RealizabilityError
from ...model.model import Model
from ...scenes.crane import margin_closed_form
from ...step.results import StepResult
from .common import (
    CRANE_G,
    CRANE_L,
    CRANE_M,
    CRANE_M0,
    CRANE_ROW,
    EPS,
    Case,
    Solver,
    fmt,
    realizability_warnings,
    recorded,
    relative,
    solvers,
)

NAME = "realizability margins"
WHAT = (
    "crane (M0 = 1, m = 0.5) at rope angles θ giving realizability margins 1e-3…1e-9 (≈ θ²·√(m/M0)), and below "
    "margin_error; direct, default QP and casadi:osqp against a closed form without cancellation"
)
EXPECTED = (
    "a RealizabilityWarning with the time exactly when margin < 1e-6; a RealizabilityError naming constraint, time "
    "and margin below 1e-12; acceleration error ≤ 10·eps/margin (growth ∝ 1/margin); QP ≡ direct"
)


def _reference(theta: float, theta_dot: float, s_ddot: float) -> np.ndarray:
    """The crane's acceleration by Cramer's rule with ``det = L sin²θ`` (no ``1 − cos²θ`` cancellation).

    ``ẍ + L cos θ θ̈ = s̈ + L sin θ θ̇²`` (the constraint twice differentiated) and
    ``cos θ ẍ + L θ̈ = −g sin θ`` (the rope's equation, which the trolley force does not enter).
    """
    s, c = math.sin(theta), math.cos(theta)
    b1, b2 = s_ddot + CRANE_L * s * theta_dot**2, -CRANE_G * s
    return np.array([(b1 - c * b2) / (s * s), (b2 - c * b1) / (CRANE_L * s * s)])


def theta_for_margin(target: float) -> float:
    """The rope angle at which the crane's margin (closed form) is ``target``."""
    from scipy.optimize import brentq

    def excess(theta: float) -> float:
        return float(margin_closed_form(theta, CRANE_M0, CRANE_M)) - target

    return float(brentq(excess, 1e-12, 1.5, xtol=1e-300, rtol=1e-15))


State = tuple[float, list[float], list[float]]


def _steps(
    model: Model, ways: list[Solver], state: State, target: float, warn_mismatches: list[str], failures: list[str]
) -> dict[str, StepResult]:
    """One step at ``state = (t, q, v)`` (margin ``target``) with every solver, by label; a RealizabilityWarning
    must carry the time exactly where the margin is below the warning threshold (else a line in ``warn_mismatches``)."""
    t, q, v = state
    results = {}
    for label, solver, backend in ways:
        with recorded() as caught:
            try:
                res = model.step(t, q, v, solver=solver, backend=backend)
            except GaussppError as exc:
                failures.append(f"{label} at margin {target:.0e}: {type(exc).__name__}: {exc}")
                continue
        results[label] = res
        warned = any(f"t={t:g}" in m for m in realizability_warnings(caught))
        if warned != (res.margin < model.margin_warn):
            warn_mismatches.append(f"{label} at margin {res.margin:.3g}: warned={warned}")
    return results


def _below_margin_error(model: Model, ways: list[Solver], state: State, failures: list[str]) -> int:
    """How many solvers stop at ``state`` (margin 1e-13, below margin_error) with a RealizabilityError naming
    constraint, time and margin; anything else is a line in ``failures``."""
    t, q, v = state
    raised_ok = 0
    for label, solver, backend in ways:
        with recorded():
            try:
                model.step(t, q, v, solver=solver, backend=backend)
                failures.append(f"{label} at margin 1e-13: no error")
            except RealizabilityError as exc:
                if exc.constraint == CRANE_ROW and exc.t == t and exc.margin < 1e-12 and f"t={t:g}" in str(exc):
                    raised_ok += 1
                else:
                    failures.append(f"{label} at margin 1e-13: incomplete RealizabilityError: {exc}")
            except GaussppError as exc:
                failures.append(f"{label} at margin 1e-13: {type(exc).__name__}: {exc}")
    return raised_ok


def _observed(figures: dict[str, float], n_targets: int, n_ways: int) -> str:
    """What the case saw, in words, from its figures."""
    at = {m: figures.get(f"error_direct@{m:.0e}", math.nan) for m in (1e-3, 1e-6, 1e-9)}
    raised_ok = int(figures["errors_below_margin_error"])
    return (
        f"{n_targets} margins 1e-3…1e-9 × {n_ways} solvers: a RealizabilityWarning with the time exactly "
        f"where the margin < 1e-6 ({int(figures['warning_mismatches'])} mismatches); at margin 1e-13 every solver "
        f"raised RealizabilityError with constraint, time and margin ({raised_ok}/{n_ways}). Relative acceleration "
        f"error (direct) {fmt(at[1e-3])} at margin 1e-3, {fmt(at[1e-6])} at 1e-6, {fmt(at[1e-9])} at 1e-9: "
        f"slope {figures['error_slope_vs_margin']:.2f} in log–log, error ≤ "
        f"{figures['worst_error_times_margin_over_eps']:.2f}·eps/margin for every solver; QP vs direct within "
        f"{figures['worst_qp_direct_difference_times_margin_over_eps']:.2f}·eps/margin (they share the reduction to "
        f"Ŝ, so the closed form is the independent check). The reported margin matches the closed form to "
        f"{fmt(figures['worst_margin_vs_closed_form'])} (relative)."
    )


def case(quick: bool = True) -> Case:
    """Margins 1e-3…1e-9 on the crane: warnings, errors, and the error's growth against the margin."""
    scene = scenes.get("crane", M0=CRANE_M0, m=CRANE_M, L=CRANE_L, g=CRANE_G, theta0=-0.3, distance=0.0)
    model = scene.model
    accel = float(scene.params["accel"])
    t, x, x_dot, theta_dot = 0.5, 0.1, 0.3, 0.2
    targets = 10.0 ** (np.arange(-3.0, -9.01, -1.0) if quick else np.arange(-3.0, -9.01, -0.5))
    ways = solvers([None, "casadi:osqp"] + ([] if quick else ["casadi:daqp", "qpsolvers:quadprog"]))
    figures: dict[str, float] = {}
    margins, errors_direct = [], []
    worst_constant = worst_difference = worst_margin_mismatch = 0.0
    warn_mismatches: list[str] = []
    failures: list[str] = []
    for target in targets:
        theta = theta_for_margin(float(target))
        ref = _reference(theta, theta_dot, accel)
        closed = float(margin_closed_form(theta, CRANE_M0, CRANE_M))
        results = _steps(model, ways, (t, [x, theta], [x_dot, theta_dot]), target, warn_mismatches, failures)
        for label, res in results.items():
            err = relative(res.a, ref)
            worst_constant = max(worst_constant, err * closed / EPS)
            worst_margin_mismatch = max(worst_margin_mismatch, abs(res.margin - closed) / closed)
            figures[f"error_{label}@{target:.0e}"] = err
        if "direct" in results:
            margins.append(closed)
            errors_direct.append(max(relative(results["direct"].a, ref), EPS / 10))
            for label, res in results.items():
                if label != "direct":
                    worst_difference = max(worst_difference, relative(res.a, results["direct"].a) * closed / EPS)
    slope = float(np.polyfit(np.log(margins), np.log(errors_direct), 1)[0]) if len(margins) > 2 else math.nan
    # below margin_error: every solver must stop with a RealizabilityError naming constraint, time, margin
    raised_ok = _below_margin_error(model, ways, (t, [x, theta_for_margin(1e-13)], [x_dot, theta_dot]), failures)
    figures.update(
        error_slope_vs_margin=slope,
        worst_error_times_margin_over_eps=worst_constant,
        worst_qp_direct_difference_times_margin_over_eps=worst_difference,
        worst_margin_vs_closed_form=worst_margin_mismatch,
        warning_mismatches=float(len(warn_mismatches)),
        errors_below_margin_error=float(raised_ok),
        failures=float(len(failures)),
    )
    verdict = (
        not warn_mismatches
        and not failures
        and raised_ok == len(ways)
        and worst_constant <= 10.0
        and worst_difference <= 10.0
        and -1.5 <= slope <= -0.5
    )
    observed = _observed(figures, len(targets), len(ways))
    return Case(NAME, WHAT, EXPECTED, observed, bool(verdict), figures, tuple(warn_mismatches[:3] + failures[:3]))
