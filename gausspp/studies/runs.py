"""One scene simulated and verified as ``gausspp run`` and ``gausspp verify`` do, and the text they print.

:func:`simulate_scene` chooses how to record (about ``samples`` intervals); :func:`summary_lines`
describes a run; :func:`thin` prepares an adaptive run's samples for the integral principle (23);
:func:`verification_lines` and :func:`verdict` describe its result.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from .. import scenes
from ..simulation import methods
from ..simulation.simulate import simulate
from ..simulation.trajectory import Trajectory
from ..verification.integral import Verification
from .tables import one_line, realizations, vector


def recording(
    method: methods.Method, t_end: float, dt: float | None, samples: int, every_step: bool
) -> tuple[float | None, Any]:
    """The ``dt`` and ``record`` of :func:`gausspp.simulate` for about ``samples`` recorded intervals.

    Adaptive methods: uniform times by dense output (or, with ``every_step``, every accepted step with
    ``T/samples`` as the largest step); fixed-step methods: every k-th step of ``dt`` (default ``T/2000``).
    """
    if method.adaptive:
        if every_step:
            return dt or t_end / samples, 1
        return dt, np.linspace(0.0, t_end, samples + 1)
    dt = dt or t_end / 2000
    return dt, max(int(np.ceil(t_end / dt - 1e-9)) // samples, 1)


def simulate_scene(
    scene: scenes.Scene,
    method: methods.Method,
    t_end: float,
    *,
    dt: float | None,
    samples: int,
    every_step: bool = False,
    **options: Any,
) -> tuple[Trajectory, float, float | None]:
    """Simulate ``scene`` to ``t_end`` recording about ``samples`` intervals (:func:`recording`); the run
    never raises for a failure midway (``throw=False``). ``options`` go to :func:`gausspp.simulate`
    (``solver``, ``backend``, ``stabilize``, ``rtol``, ``atol``). Returns the trajectory, the wall time
    in s and the ``dt`` used."""
    dt, record = recording(method, t_end, dt, samples, every_step)
    start = time.perf_counter()
    traj = simulate(
        scene.model,
        scene.q0,
        scene.v0,
        t_end,
        lam0=scene.lam0,
        dt=dt,
        method=method.name,
        record=record,
        throw=False,
        **options,
    )
    return traj, time.perf_counter() - start, dt


def thin(traj: Trajectory, gap: float) -> Trajectory:
    """Drop samples closer than ``gap`` to the previous kept one (the last sample is kept).

    Adaptive integrators can end on a step of round-off size; such near-duplicate nodes spoil the
    spline that (23) differentiates. The two samples of a velocity jump (an impact: same time,
    before and after) are both kept: verification cuts the path there.
    """
    t, keep = traj.t, [0]
    for i in range(1, t.size):
        jump = t[i] <= t[i - 1]
        if jump and keep[-1] != i - 1:
            keep.append(i - 1)  # the sample just before the jump
        if jump or t[i] - t[keep[-1]] >= gap:
            keep.append(i)
    if t.size and keep[-1] != t.size - 1:
        keep[-1] = t.size - 1
    if len(keep) == t.size:
        return traj
    idx = np.array(keep)
    fields = {
        k: getattr(traj, k)[idx]
        for k in traj.__dataclass_fields__
        if isinstance(getattr(traj, k), np.ndarray) and getattr(traj, k).shape[:1] == t.shape
    }
    return replace(traj, **fields)


#: What the margin row means, in one line.
MARGIN_MEANING = "σ_min of the normalized J A⁻¹ D: 1 = one ideal row, < 1 rows or directions leaning together, 0 = lost"
#: Vectors longer than this are shown by their first and last entries.
SHOWN = 8


def named(values: np.ndarray, names: tuple[str, ...] = (), rate: bool = False) -> str:
    """``x = 0.772 m, z = −0.636 m`` from names written ``"x (m)"`` (``rate``: ``x′ = … m/s``); a plain vector
    without names; the first and last entries only beyond :data:`SHOWN` (with the count)."""
    values = np.asarray(values, float).ravel()
    if len(names) != values.size:
        text = vector(values if values.size <= SHOWN else values[:SHOWN])
        return text if values.size <= SHOWN else f"{text[:-1]}, … ] ({values.size} values)"
    items = []
    for name, value in zip(names, values, strict=True):
        label, _, unit = name.partition(" (")
        unit = unit.rstrip(")")
        if rate:
            label, unit = f"{label}′", (f"{unit}/s" if unit else "1/s")
        items.append(f"{label} = {value:.6g}" + (f" {unit}" if unit else ""))
    if len(items) > SHOWN:
        items = [*items[: SHOWN - 2], "…", *items[-2:]]
        return ", ".join(items) + f" ({values.size} values)"
    return ", ".join(items)


def setting(traj: Trajectory, dt: float | None, rtol: float) -> str:
    """The run's accuracy setting: ``rtol …`` for adaptive methods, ``dt …`` otherwise."""
    return f"rtol {rtol:g}" if methods.get(traj.method).adaptive else f"dt {dt:g}"


def _state_rows(scene: scenes.Scene, traj: Trajectory) -> list[tuple[str, str]]:
    """Final state, residual, energy balance, margin, events, contacts, saturation, error against the exact motion."""
    names = tuple(scene.coordinates or traj.labels.coordinate or ())
    rows = [("time", f"t = {traj.t[0]:g} → {traj.t[-1]:.6g}"), ("final q", named(traj.q[-1], names))]
    same = len(names) == traj.v.shape[1] == traj.q.shape[1]  # q̇ = v: the velocities are the coordinates' rates
    rows.append(("final v", named(traj.v[-1], names if same else (), rate=True)))
    if traj.lam.shape[1]:
        rows.append(("final λ", named(traj.lam[-1], traj.labels.lam_state)))
    rows.append(("final u", named(traj.u[-1], traj.labels.unknown)))
    rows.append(("max |Φ|, |g|", f"{traj.max_residual():.2e}"))
    balance = np.abs(traj.energy_balance())
    rows.append(
        (
            "energy balance",
            f"{np.nanmax(balance):.2e} (largest |ΔE − W_reaction − W_forces|)"
            if np.isfinite(balance).any()
            else "— (the model does not know its energy or its forces' power)",
        )
    )
    if traj.margin.size:
        rows.append(("margin", f"{traj.margin.min():.4g} … {traj.margin.max():.4g} ({MARGIN_MEANING})"))
    if traj.events:
        kinds = {k: sum(ev["kind"] == k for ev in traj.events) for k in dict.fromkeys(ev["kind"] for ev in traj.events)}
        rows.append(("events", ", ".join(f"{n} {k}" for k, n in kinds.items())))
    if traj.contact_force.shape[1]:
        rows.append(("contact force", f"{vector(traj.contact_force[-1])} at the end"))
    if traj.saturated.size and traj.saturated.any():
        share = traj.saturated.any(axis=1).mean()
        rows.append(("saturation", f"{share:.0%} of the samples, tracking error up to {traj.tracking_error.max():.3g}"))
    if scene.exact is not None and traj.status != "failed":
        q_ex, v_ex = scene.exact(float(traj.t[-1]))
        err = float(np.abs(np.concatenate([traj.q[-1] - q_ex, traj.v[-1] - v_ex])).max())
        rows.append(("vs exact", f"{err:.2e} (largest final-state error against the known motion)"))
    return rows


def summary_lines(scene: scenes.Scene, traj: Trajectory, wall: float, dt: float | None, rtol: float) -> list[str]:
    """The summary ``gausspp run`` prints: realizations, method, status, cost, then the state (if any)."""
    rows = [
        ("realizations", realizations(scene.model)),
        ("method", f"{traj.method} ({setting(traj, dt, rtol)}) · step by {traj.solver}"),
        ("status", traj.status + (f" — {one_line(traj.message)}" if traj.message else "")),
        ("steps", f"{traj.steps} steps, {len(traj)} samples, {traj.rhs_evaluations} step evaluations, {wall:.3g} s"),
    ]
    if len(traj):
        rows += _state_rows(scene, traj)
    return [f"  {k:15s} {v}" for k, v in rows]


def verification_lines(result: Verification, wall: float) -> list[str]:
    """The figures of a verification by (23): gap, tolerance, cost, the worst δx if not a motion, the pieces."""
    worst = int(np.argmax(np.abs(result.delta_x).max(axis=1))) if result.delta_x.size else 0
    lines = [
        ("relative gap", f"{result.relative_gap:.3e}  (on every other node: {result.coarse_relative_gap:.3e})"),
        ("tolerance", f"{result.tolerance:.3e}"),
        ("verification", f"{result.t.size} nodes, {wall:.3g} s"),
    ]
    if not result.is_motion:
        lines.append(("largest δx", f"at t = {result.t[worst]:.6g}: {vector(result.delta_x[worst])}"))
    if result.pieces or result.skipped:
        lines += [("pieces", line) for line in result.message.splitlines()[1:]]
    return [f"  {key:14s} {value}" for key, value in lines]


def verdict(result: Verification) -> tuple[str, str]:
    """The verdict of (23) and its reason, as ``gausspp verify`` prints them."""
    if result.is_motion:
        return "a motion of the model", "(relative gap ≤ tolerance)"
    return (
        "NOT a motion of the model",
        "(relative gap > tolerance: the reaction does work on an admissible variation δx)",
    )
