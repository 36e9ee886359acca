"""Success means within tolerance: a run that reached ``t_end`` is a success only if its recorded residuals and
its energy balance stay within the run's ``constraint_tol``.

Two thresholds judge a recorded motion. ``drift_tol`` (default 1e-3, :mod:`.residual_audit`,
:mod:`.energy_audit`) tells a motion that *left* its constraints — a step far too long, a step across a
singular position — and ends the run as failed. ``constraint_tol`` (default 1e-8, the same bound the initial
data must meet) is the accuracy the run promises: every sample must keep

* ``|g_i| ≤ constraint_tol·s_g,i`` and ``|Φ_i| ≤ constraint_tol·s_Φ,i`` for every constraint row, each against
  its own scale (:func:`~gausspp.model.run_scales.row_scales`),
* ``|E − E₀ − W_R − W_F| ≤ ENERGY_SHARE·constraint_tol`` of the run's energy scale where the balance closes
  (:func:`~gausspp.model.run_scales.energy_scale`), or within its round-off floor.

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
from ..model.run_scales import RunScales, scales_at_first
from .energy_audit import ENERGY_SHARE, beyond, closes
from .residual_audit import residual_audit
from .trajectory import Trajectory

#: The status of a run that reached ``t_end`` with a residual or an energy balance beyond ``constraint_tol``.
DRIFTED = "drifted"


def within_tolerance(
    model: Model, traj: Trajectory, constraint_tol: float, scales: RunScales | None = None
) -> Trajectory:
    """``traj`` unchanged if every sample keeps ``constraint_tol`` (module docstring), else marked
    ``"drifted"`` with a warning that names the first sample beyond it. ``scales``: the run's, read at the first
    sample if not given."""
    if traj.status != "success" or not traj.t.size:
        return traj
    n = traj.t.size
    y = np.column_stack([traj.q, traj.v, traj.lam, traj.work_reaction, traj.work_forces])
    scales = scales or scales_at_first(model, traj.t, y)
    _, rows = residual_audit(model, traj.t, y, traj.g, traj.residual, constraint_tol, n, scales)
    energy = _energy_beyond(model, traj, y, constraint_tol, scales)
    found = [e for e in (rows, energy) if e is not None]
    if not found:
        return traj
    first = min(found, key=lambda e: e.t)
    if first is energy:
        what = f"its energy balance E − E₀ − W_R − W_F was {first.residual:.3g}, beyond {ENERGY_SHARE:g}·constraint_tol"
        what += " of the run's energy scale"
    else:
        what = f"the constraint {first.constraint!r} was off by {first.residual:.3g}, beyond constraint_tol"
        what += " of the row's own scale"
    message = (
        f"the run reached t={traj.t[-1]:.6g} but not within constraint_tol={constraint_tol:.3g}: first at "
        f"t={first.t:.6g}, {what}; a shorter step (dt), tighter rtol/atol or stabilize='baumgarte' keeps the motion "
        "closer to its constraints, a larger constraint_tol accepts this accuracy"
    )
    warnings.warn(message, DriftWarning, stacklevel=4)
    return replace(traj, status=DRIFTED, message=message)


def _energy_beyond(model: Model, traj: Trajectory, y: np.ndarray, tol: float, scales: RunScales) -> DriftError | None:
    """The first sample whose energy balance leaves ``ENERGY_SHARE·tol`` of the whole run's energy scale (above its
    round-off floor, :func:`~gausspp.model.run_scales.energy_scale`), or ``None``."""
    if traj.t.size < 2 or not closes(model):
        return None
    balance = traj.energy_balance()
    off = beyond(model, scales, traj.t, y, traj.energy, balance, tol, None)
    if off is None:
        return None
    i = off[0]
    return DriftError("", t=float(traj.t[i]), constraint="energy balance", residual=float(balance[i]))
