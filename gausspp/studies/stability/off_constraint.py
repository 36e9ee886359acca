"""Initial data off the constraint: InitialDataError naming it, and ``stabilize="project"``."""

from __future__ import annotations

from typing import Any

import numpy as np

from ... import scenes
from ...errors import GaussppError, InitialDataError
from ...model.model import Model
from ...simulation.simulate import simulate
from ...simulation.trajectory import Trajectory
from .common import CRANE_G, CRANE_L, CRANE_M, CRANE_M0, CRANE_ROW, Case, recorded

NAME = "initial data off the constraint"
WHAT = (
    "gp.simulate from initial data off the constraint: two-masses servo (Φ = 0.5), pendulum (g = 1e-3), "
    "rigid-body servo (Φ = 0.3), crane (g = 1e-3, 1e-2, 0.3 and 5, and g = 1e-3 at the vertical rope, where the "
    "servo cannot move the payload); and the same with stabilize='project'"
)
EXPECTED = (
    "InitialDataError naming the constraint, the time and the value; with stabilize='project' the run starts on the "
    "constraint (|g|, |Φ| ≤ 1e-12) near the given data (moved by at most 10× the first Newton step along the "
    "realization's directions) — or, where the projection cannot get there (singular S, far data), an "
    "InitialDataError that says the projection failed, without advising stabilize='project'"
)

#: Allowed displacement of the projected ``q``, in first Newton steps.
NEAR = 10.0


def _vec(x: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.3g}" for v in np.ravel(x)) + ")"


def _residual_g(model: Model, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.asarray(model.kernel("direct")(0.0, q, v, np.zeros(model.n_lam), np.zeros(2))["g"], float).ravel()


def _newton_step(model: Model, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``A⁻¹D (J A⁻¹D)⁻¹ g``: the projection's first step on ``q`` (all rows holonomic, ``q̇ = v``); 0 if none."""
    if len(model.holonomic_rows) != len(model.row_names):
        return np.zeros(model.nq)  # velocity-level constraints: q is not moved
    p = model.step_data(0.0, q, v)
    AinvD = np.linalg.solve(p.A, p.D)
    with np.errstate(all="ignore"):
        return np.asarray(AinvD @ np.linalg.lstsq(p.J @ AinvD, _residual_g(model, q, v), rcond=None)[0])


def _backtracking_projection(model: Model, q: np.ndarray, v: np.ndarray) -> np.ndarray | None:
    """The same Newton iteration with step halving until ``|g|`` decreases: a point on g = 0 near ``q``."""
    for _ in range(100):
        g = float(np.max(np.abs(_residual_g(model, q, v))))
        if g <= 1e-13:
            return q
        dq, scale = _newton_step(model, q, v), 1.0
        while scale > 1e-8 and not float(np.max(np.abs(_residual_g(model, q - scale * dq, v)))) < g:
            scale /= 2
        q = q - scale * dq
    return None


Setup = tuple[str, scenes.Scene, np.ndarray, np.ndarray, str, float]


def _setups(quick: bool) -> tuple[list[Setup], scenes.Scene]:
    """The initial data off the constraint: (label, scene, q0, v0, the constraint's name, the value off it);
    and the two-masses scene (its projection must move only mass 1)."""
    two = scenes.get("two-masses", realization="servo")
    pend = scenes.get("pendulum")
    body = scenes.get("rigid-body-servo", n=(1.0, 0.2, 0.1))
    crane = scenes.get("crane", M0=CRANE_M0, m=CRANE_M, L=CRANE_L, g=CRANE_G)
    l_axis = np.asarray(body.params["l"], float)
    vertical = np.array([crane.q0[0] + CRANE_L * np.sin(crane.q0[1]), 0.0])  # same payload position, rope vertical
    setups: list[Setup] = [
        ("two-masses servo, Φ = 0.5", two, two.q0, np.array([0.0, 0.5]), "rod", 0.5),
        ("pendulum, g = 1e-3", pend, pend.q0 + np.array([1e-3, 0.0, 0.0]), pend.v0, "pin-x", 1e-3),
        ("rigid-body servo, Φ = 0.3", body, body.q0, body.v0 + 0.3 * l_axis, "(ω, l) = 0", 0.3),
        ("crane, g = 1e-3", crane, crane.q0 + np.array([1e-3, 0.0]), crane.v0, CRANE_ROW, 1e-3),
        ("crane, g = 1e-2", crane, crane.q0 + np.array([1e-2, 0.0]), crane.v0, CRANE_ROW, 1e-2),
        ("crane, g = 0.3", crane, crane.q0 + np.array([0.3, 0.0]), crane.v0, CRANE_ROW, 0.3),
        ("crane, g = 5", crane, crane.q0 + np.array([5.0, 0.0]), crane.v0, CRANE_ROW, 5.0),
        ("crane at the vertical rope, g = 1e-3", crane, vertical + np.array([1e-3, 0.0]), np.zeros(2), CRANE_ROW, 1e-3),
    ]
    if not quick:
        setups += [
            ("pendulum, g = 0.1", pend, pend.q0 + np.array([0.1, 0.0, 0.0]), pend.v0, "pin-x", 0.1),
            ("crane, g = 0.1", crane, crane.q0 + np.array([0.1, 0.0]), crane.v0, CRANE_ROW, 0.1),
            ("crane, g = 1", crane, crane.q0 + np.array([1.0, 0.0]), crane.v0, CRANE_ROW, 1.0),
        ]
    return setups, two


def _named_error(setup: Setup, options: dict[str, Any], notes: list[str]) -> int:
    """1 if the run without stabilization raises InitialDataError naming the constraint, t=0 and the value;
    else 0, with a note saying what happened instead."""
    label, scene, q0, v0, row, value = setup
    try:
        simulate(scene.model, q0, v0, 0.05, **options)
        notes.append(f"{label}: no InitialDataError")
    except InitialDataError as exc:
        msg = str(exc)
        if repr(row) in msg and "t=0" in msg and f"{value:.3g}" in msg:
            return 1
        notes.append(f"{label}: InitialDataError without constraint/time/value: {msg}")
    except GaussppError as exc:
        notes.append(f"{label}: {type(exc).__name__}: {exc}")
    return 0


def _projected_run(setup: Setup, options: dict[str, Any], notes: list[str]) -> tuple[Trajectory | None, int]:
    """The run with ``stabilize="project"``, or None and 1 if it fails with an InitialDataError that clearly says
    the projection failed (None and 0, with a note, for any other failure)."""
    label, scene, q0, v0, _, _ = setup
    try:
        return simulate(scene.model, q0, v0, 0.05, stabilize="project", **options), 0
    except InitialDataError as exc:
        msg = str(exc)
        if "projecting" in msg and "stabilize='project'" not in msg:
            return None, 1
        notes.append(f"{label}: unclear InitialDataError after projection: {msg[:160]}")
    except GaussppError as exc:
        notes.append(f"{label}: {type(exc).__name__} after projection: {str(exc)[:160]}")
    return None, 0


def _projected_near(setup: Setup, traj: Trajectory, notes: list[str], far: list[str]) -> int:
    """1 if the projected run starts on the constraint within :data:`NEAR` first Newton steps of the data; else
    0, with a note (off the constraint) or a line in ``far`` (a far root, and where a backtracking Newton lands)."""
    label, scene, q0, v0, _, _ = setup
    start = float(max(np.max(np.abs(traj.g[0])), np.max(np.abs(traj.residual[0]))))
    moved = float(np.max(np.abs(traj.q[0] - q0)))
    first = float(np.max(np.abs(_newton_step(scene.model, q0, v0))))
    if start > 1e-12:  # pragma: no cover - simulate's own check catches this
        notes.append(f"{label}: starts {start:.2g} off the constraint")
    elif moved > NEAR * first + 1e-12:
        near = _backtracking_projection(scene.model, q0, v0)
        far.append(
            f"{label}: q0 = {_vec(q0)} projected to {_vec(traj.q[0])} "
            f"(moved {moved:.2g}, the first Newton step is {first:.2g})"
            + (
                f"; a backtracking Newton from the same data lands at {_vec(near)} "
                f"(moved {float(np.max(np.abs(near - q0))):.2g})"
                if near is not None
                else ""
            )
        )
    else:
        return 1
    return 0


def _observed(n: int, named: int, projected: int, refused: int, far: list[str], notes: list[str]) -> str:
    """What the case saw, in words, for ``n`` setups."""
    return (
        f"Without stabilization {named}/{n} setups raise InitialDataError naming the constraint, t=0 and "
        f"the value. With stabilize='project' {projected} start on the constraint (≤ 1e-12) within {NEAR:g} first "
        "Newton steps of the data (the two-masses servo moves only mass 1, along A⁻¹D), and "
        f"{refused} end in an InitialDataError saying the projection failed (the singular vertical rope: NaN; far "
        "data: no convergence in 50 steps)"
        + (f"; {len(far)} {'lands' if len(far) == 1 else 'land'} far away: " + "; ".join(far) if far else "")
        + "."
        + (" Other: " + "; ".join(notes) + "." if notes else "")
    )


def _far_root_problem(far: list[str]) -> str:
    """The problem report for projections that land on a far root."""
    return (
        "stabilize='project' accepts a far root: the undamped Newton iteration of the initial projection "
        "(drift.projection_function, repeated by simulate._project_initial until |g|, |Φ| are small) can jump "
        "to a point on the constraint arbitrarily far from the data and start there without a word — "
        + "; ".join(far)
        + ". Right: damp the Newton steps (or bound |Δq|) and raise InitialDataError when no point within a few "
        "steps is found. Repro: c = gp.scenes.get('crane'); gp.simulate(c.model, c.q0 + [0.3, 0], c.v0, 0.05, "
        "dt=0.01, stabilize='project').q[0]."
    )


def case(quick: bool = True) -> Case:
    """InitialDataError naming the constraint; stabilize='project' starts on it near the data, or fails clearly."""
    setups, two = _setups(quick)
    named, projected, refused = 0, 0, 0
    notes: list[str] = []
    far: list[str] = []
    for setup in setups:
        options: dict[str, Any] = dict(dt=0.01, method="rk4", solver="direct")
        with recorded():
            named += _named_error(setup, options, notes)
            traj, clear = _projected_run(setup, options, notes)
        if traj is None:
            refused += clear
            continue
        projected += _projected_near(setup, traj, notes, far)
        if setup[1] is two and not np.allclose(traj.v[0], [0.5, 0.5], rtol=0, atol=1e-15):
            notes.append(f"{setup[0]}: projected to v = {traj.v[0]}, not along A⁻¹D = (1/m1, 0)")
    f = {
        "setups": float(len(setups)),
        "named_errors": float(named),
        "projected_near": float(projected),
        "projection_refused_clearly": float(refused),
        "projected_far": float(len(far)),
    }
    verdict = named == len(setups) and projected + refused == len(setups) and not far and not notes
    observed = _observed(len(setups), named, projected, refused, far, notes)
    problems = [_far_root_problem(far)] if far else []
    return Case(NAME, WHAT, EXPECTED, observed, bool(verdict), f, tuple(problems + notes[:2]))
