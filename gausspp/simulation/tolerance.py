"""Success means within tolerance: a run that reached ``t_end`` is a success only if its recorded residuals and
its energy balance stay within the run's ``constraint_tol``.

Two thresholds judge a recorded motion. ``drift_tol`` (default 1e-3, :mod:`.residual_audit`,
:mod:`.energy_audit`) tells a motion that *left* its constraints — a step far too long, a step across a
singular position — and ends the run as failed. ``constraint_tol`` (default 1e-8, the same bound the initial
data must meet) is the accuracy the run promises: every sample must keep

* ``|g_i| ≤ constraint_tol·(1 + ‖q‖∞)`` and ``|Φ_i| ≤ constraint_tol·(1 + ‖v‖∞)`` for every constraint row,
* ``|E − E₀ − W_R − W_F| ≤ ENERGY_SHARE·constraint_tol`` of the run's energy scale where the balance closes.

A run that finished but broke one of them is not called a success: its status is ``"drifted"``, its message
names the first sample, the row (or ``"energy balance"``) and the value, and a :class:`~gausspp.DriftWarning`
says the same. It is not raised: the trajectory is whole and is the method's honest answer at the step it was
given (``rk4`` drifts as ``O(dt⁴)``), and the fix is the user's choice — a shorter step, tighter ``rtol/atol``,
``stabilize="baumgarte"``, or a ``constraint_tol`` that states the accuracy the study needs.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from ..errors import DriftError, DriftWarning
from ..model.model import Model
from .energy_audit import ENERGY_SHARE, closes, kinetic_energies
from .residual_audit import residual_audit
from .trajectory import Trajectory

#: The status of a run that reached ``t_end`` with a residual or an energy balance beyond ``constraint_tol``.
DRIFTED = "drifted"


def within_tolerance(model: Model, traj: Trajectory, constraint_tol: float) -> Trajectory:
    """``traj`` unchanged if every sample keeps ``constraint_tol`` (module docstring), else marked
    ``"drifted"`` with a warning that names the first sample beyond it."""
    if traj.status != "success" or not traj.t.size:
        return traj
    n = traj.t.size
    y = np.column_stack([traj.q, traj.v, traj.lam, traj.work_reaction, traj.work_forces])
    _, rows = residual_audit(model, traj.t, y, traj.g, traj.residual, constraint_tol, n)
    energy = _energy_beyond(model, traj, y, constraint_tol)
    found = [e for e in (rows, energy) if e is not None]
    if not found:
        return traj
    first = min(found, key=lambda e: e.t)
    if first is energy:
        what = f"its energy balance E − E₀ − W_R − W_F was {first.residual:.3g}, beyond {ENERGY_SHARE:g}·constraint_tol"
        what += " of the run's energy scale"
    else:
        what = f"the constraint {first.constraint!r} was off by {first.residual:.3g}, beyond constraint_tol"
        what += " relative to the state (|g| ≤ tol·(1 + ‖q‖∞), |Φ| ≤ tol·(1 + ‖v‖∞))"
    message = (
        f"the run reached t={traj.t[-1]:.6g} but not within constraint_tol={constraint_tol:.3g}: first at "
        f"t={first.t:.6g}, {what}; a shorter step (dt), tighter rtol/atol or stabilize='baumgarte' keeps the motion "
        "closer to its constraints, a larger constraint_tol accepts this accuracy"
    )
    warnings.warn(message, DriftWarning, stacklevel=4)
    return replace(traj, status=DRIFTED, message=message)


def _energy_beyond(model: Model, traj: Trajectory, y: np.ndarray, tol: float) -> DriftError | None:
    """The first sample whose energy balance leaves ``ENERGY_SHARE·tol`` of the whole run's energy scale (the
    largest kinetic energy plus the largest exchanges ``|E − E₀| + |W_R| + |W_F|``), or ``None``."""
    if traj.t.size < 2 or not closes(model):
        return None
    balance = traj.energy_balance()
    exchange = np.abs(traj.energy - traj.energy[0]) + np.abs(traj.work_reaction - traj.work_reaction[0])
    exchange += np.abs(traj.work_forces - traj.work_forces[0])
    scale = np.nanmax(exchange) + kinetic_energies(model, traj.t, y, traj.t.size).max()
    off = np.flatnonzero(~(np.abs(balance) <= ENERGY_SHARE * tol * scale))
    if not off.size:
        return None
    i = int(off[0])
    return DriftError("", t=float(traj.t[i]), constraint="energy balance", residual=float(balance[i]))
