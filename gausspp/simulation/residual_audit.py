"""Success means within tolerance: the recorded constraint residuals checked before a run is called a success.

Every step answers at the state it is given, including a state off the constraint; nothing in a single step
notices that the motion as a whole has left its constraints. That happens with a fixed step too long for the
motion (``rk4`` with ``dt = 10`` on a pendulum: ``|g| = 100``, each step answered) and with a step across a
singular position that lands off the branch the motion was on. :func:`residual_audit` compares the recorded
``g(q, t)`` and ``Φ(q, v, t)`` of every sample with the run's ``drift_tol``, relative to each row's own scale
(``|g_i| ≤ drift_tol·s_g,i``, ``|Φ_i| ≤ drift_tol·s_Φ,i``, :func:`~gausspp.model.run_scales.row_scales`: the
size of the terms the row adds up, never the largest coordinate of the state): a method's own drift, ``O(dt⁴)``
for ``rk4`` or ``O(rtol)`` for an adaptive one, passes; a motion that left the constraint does not. The first
sample beyond it ends the run as failed with a :class:`~gausspp.DriftError` naming the time, the row and the
value. That sample is kept, so that the trajectory shows the departure; later ones are dropped. A model with
bounded actuators is not audited: a saturated actuator falls short of its constraint by design
(``Trajectory.tracking_error``).
"""

from __future__ import annotations

import numpy as np

from ..errors import DriftError
from ..model.model import Model
from ..model.run_scales import RunScales, row_scales, scales_at_first, within

#: What the fix is, in every message.
ADVICE = (
    "a shorter step (dt), tighter rtol/atol or stabilize='baumgarte' keeps the motion on the constraint; a "
    "larger drift_tol accepts this drift"
)


def residual_audit(
    model: Model,
    t: np.ndarray,
    y: np.ndarray,
    g: np.ndarray,
    Phi: np.ndarray,
    tol: float,
    n: int,
    scales: RunScales | None = None,
) -> tuple[int, DriftError | None]:
    """The samples to keep of the first ``n`` and the failure, if a residual of ``g`` or ``Phi`` (each
    ``(N, k)``) exceeds ``tol`` of its row's scale over the samples (NaN counts as beyond it). ``scales``: the
    run's (:func:`~gausspp.model.run_scales.run_scales`), read at the first sample if not given."""
    if n == 0 or model.k == 0 or model.bounded:
        return n, None
    s_g, s_Phi, floor_g, floor_Phi = row_scales(model, scales or scales_at_first(model, t, y), t, y, n)
    g_rel, Phi_rel = within(g[:n], s_g, floor_g, tol), within(Phi[:n], s_Phi, floor_Phi, tol)
    g_off, Phi_off = ~(g_rel <= 1.0), ~(Phi_rel <= 1.0)
    samples = np.flatnonzero((g_off | Phi_off).any(axis=1))
    if not samples.size:
        return n, None
    i = int(samples[0])
    relative = np.where(g_off[i], g_rel[i], Phi_rel[i])
    row = int(np.argmax(np.nan_to_num(np.where(g_off[i] | Phi_off[i], relative, -1.0), nan=np.inf)))
    what, value, size = (
        ("g(q, t)", g[i, row], s_g[i, row]) if g_off[i, row] else ("Φ(q, v, t)", Phi[i, row], s_Phi[i, row])
    )
    name = model.row_names[row]
    return i + 1, DriftError(
        f"the motion left the constraint {name!r} at t={t[i]:.6g}: {what} = {value:.3g} exceeds drift_tol = {tol:g} "
        f"of the row's scale {size:.3g} (samples after it are dropped); {ADVICE}",
        t=float(t[i]),
        constraint=name,
        residual=float(value),
    )
