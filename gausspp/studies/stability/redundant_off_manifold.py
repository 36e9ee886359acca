"""Part C of the redundant-constraints study: consistent redundant rows off the constraint manifold.

The pendulum held by two pins and a distance row, moved off the manifold by δ: the direct formula must refuse
the redundant rows naming them, every QP backend must return the minimal model's acceleration (or, if the registry
declares it approximate, refuse clearly), never a silently wrong answer.
"""

from __future__ import annotations

import numpy as np

from ...errors import QPSolveError, RealizabilityError
from ...step import qp
from .common import fmt
from .redundant_setups import (
    DRIFTS,
    PINS,
    SCAN_DRIFTS,
    Findings,
    Section,
    attempt,
    clear_direct,
    kind,
    off_tol,
    pendulum_state,
    pendulum_with_distance,
    qp_ways,
    refuses_redundancy,
)


def off_manifold_states(quick: bool) -> list[tuple[float, float]]:
    """``(φ, δ)``: φ = 0.7 and 0 at the drifts :data:`DRIFTS`, then a scan of the angles at :data:`SCAN_DRIFTS`."""
    drifts = DRIFTS if quick else tuple(float(d) for d in 10.0 ** np.arange(-12.0, -1.9, 0.5))
    scan = np.linspace(-3.0, 3.0, 61 if quick else 241)[:: 5 if quick else 1]
    return [(p, d) for p in (0.7, 0.0) for d in drifts] + [(float(p), d) for p in scan for d in SCAN_DRIFTS]


def off_manifold_section(found: Findings, quick: bool) -> Section:
    """C. Pins + distance off the manifold by δ: every QP backend must give the minimal model's acceleration.

    At φ = 0.7 the distance row becomes independent of the pins (``J A⁻¹ Jᵀ`` nearly singular, margin ∝ δ²); at
    φ = 0 it stays parallel to pin-x's row and its right-hand side disagrees by the drift.
    """
    scene, with_distance = pendulum_with_distance()
    states = off_manifold_states(quick)
    ways = qp_ways()
    errors: dict[str, list[str]] = {}  # QP backend → its errors (consistent rows: each is a failure)
    refusals: dict[str, list[str]] = {}  # an approximate backend (qp.APPROXIMATE) → states it clearly refused
    direct_refusals = direct_named = answers = 0
    direct_other: list[str] = []
    max_err = max_ratio = 0.0
    for phi, drift in states:
        q, v = pendulum_state(phi, 1.3, drift)
        ref = scene.model.step(0.0, q, v, solver="direct").a
        where = f"pins + distance {drift:.0e} off the manifold at φ = {phi:.2f}"
        out, _ = attempt(with_distance, q, v, "direct", None)
        found.judge(out, ref, off_tol(drift), f"{where}, direct")
        direct_refusals += refuses_redundancy(out)
        direct_named += clear_direct(out, PINS)
        if not refuses_redundancy(out):
            direct_other.append(f"{where}: {kind(out)}: {out}")
        for label, solver, backend in ways:
            out, _ = attempt(with_distance, q, v, solver, backend)
            err = found.judge(out, ref, off_tol(drift), f"{where}, {label}")
            if err is None:
                clear_refusal = isinstance(out, QPSolveError | RealizabilityError) and "try another backend" in str(out)
                if backend in qp.APPROXIMATE and clear_refusal:  # declared ~1e-7 accurate: refusing is its answer
                    refusals.setdefault(label, []).append(where)
                else:
                    errors.setdefault(label, []).append(f"{where}: {kind(out)}: {out}")
                continue
            answers += 1
            max_err, max_ratio = max(max_err, err), max(max_ratio, err / drift)
    steps = len(states) * len(ways)
    f = dict(
        off_manifold_states=float(len(states)),
        off_manifold_qp_steps=float(steps),
        off_manifold_qp_answers=float(answers),
        off_manifold_qp_errors=float(steps - answers - sum(map(len, refusals.values()))),
        off_manifold_approximate_refusals=float(sum(map(len, refusals.values()))),
        off_manifold_max_error=max_err,
        off_manifold_error_over_drift=max_ratio,
        off_manifold_direct_refusals=float(direct_refusals),
        off_manifold_direct_errors_naming_constraints=float(direct_named),
    )
    observed = (
        f"Off the manifold ({len(states)} states: φ = 0.7 and 0 at δ = {DRIFTS[0]:.0e}…{DRIFTS[-1]:.0e}, and "
        f"δ = {', '.join(f'{d:.0e}' for d in SCAN_DRIFTS)} over the angles): the {len(ways)} QP backends answer "
        f"{answers}/{steps} times, within {fmt(max_err)} of the minimal model at the same state (≤ {fmt(max_ratio)}·δ)"
        + (
            "; errors: " + "; ".join(f"{b}: {len(e)} (first: {e[0][:200]})" for b, e in errors.items())
            if errors
            else ""
        )
        + "".join(
            f"; {b} (declared approximate) refuses {len(w)} nearly singular steps, naming the exact backends"
            for b, w in refusals.items()
        )
        + f". Direct refuses the redundant rows {direct_refusals}/{len(states)} times, naming the constraints in "
        f"{direct_named}."
    )
    return Section(f, observed, _off_manifold_problems(errors, direct_other, direct_named, direct_refusals, states))


def _off_manifold_problems(
    errors: dict[str, list[str]],
    direct_other: list[str],
    direct_named: int,
    direct_refusals: int,
    states: list[tuple[float, float]],
) -> list[str]:
    """What went wrong off the manifold: a QP backend raising, the direct formula not refusing or not naming."""
    problems = []
    if errors:
        problems.append(
            "Consistent redundant rows off the constraint manifold: a QP backend raises instead of returning the "
            "minimal model's acceleration — "
            + "; ".join(f"{b}: {len(e)}/{len(states)} states, e.g. {e[0][:300]}" for b, e in errors.items())
            + ". Repro: `sc, m = gausspp.studies.stability.redundant.pendulum_with_distance()`; "
            "q, v = gausspp.studies.stability.redundant.pendulum_state(φ, 1.3, δ); m.step(0, q, v, backend=...)."
        )
    if direct_other:
        problems.append("Off the manifold, solver='direct' does not refuse the redundant rows: " + direct_other[0])
    if direct_named < direct_refusals:
        problems.append(
            f"Off the manifold, {direct_refusals - direct_named} of solver='direct''s {direct_refusals} refusals do "
            f"not name the constraints {', '.join(map(repr, PINS))} in their message (the error's .constraint "
            "does): Model.step's 'redundant on the constraint manifold' message. Repro: "
            "`_, m = gausspp.studies.stability.redundant.pendulum_with_distance()`; q, v = "
            "gausspp.studies.stability.redundant.pendulum_state(0.7, 1.3, 1e-3); m.step(0, q, v, solver='direct')."
        )
    return problems
