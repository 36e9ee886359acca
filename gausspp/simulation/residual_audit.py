"""Success means within tolerance: the recorded constraint residuals checked before a run is called a success.

Every step answers at the state it is given, including a state off the constraint; nothing in a single step
notices that the motion as a whole has left its constraints. That happens with a fixed step too long for the
motion (``rk4`` with ``dt = 10`` on a pendulum: ``|g| = 100``, each step answered) and with a step across a
singular position that lands off the branch the motion was on. :func:`residual_audit` compares the recorded
``g(q, t)`` and ``Φ(q, v, t)`` of every sample with the run's ``drift_tol``, relative to the size of the state
(``|g_i| ≤ drift_tol·(1 + ‖q‖∞)``, ``|Φ_i| ≤ drift_tol·(1 + ‖v‖∞)``: a method's own drift, ``O(dt⁴)`` for
``rk4`` or ``O(rtol)`` for an adaptive one, passes; a motion that left the constraint does not). The first
sample beyond it ends the run as failed with a :class:`~gausspp.DriftError` naming the time, the row and the
value. That sample is kept, so that the trajectory shows the departure; later ones are dropped. A model with
bounded actuators is not audited: a saturated actuator falls short of its constraint by design
(``Trajectory.tracking_error``).
"""

from __future__ import annotations

import numpy as np

from ..errors import DriftError
from ..model.model import Model

#: What the fix is, in every message.
ADVICE = (
    "a shorter step (dt), tighter rtol/atol or stabilize='baumgarte' keeps the motion on the constraint; a "
    "larger drift_tol accepts this drift"
)


def residual_audit(
    model: Model, t: np.ndarray, y: np.ndarray, g: np.ndarray, Phi: np.ndarray, tol: float, n: int
) -> tuple[int, DriftError | None]:
    """The samples to keep of the first ``n`` and the failure, if a residual of ``g`` or ``Phi`` (each
    ``(N, k)``) exceeds ``tol`` relative to the state ``y`` (NaN counts as beyond it)."""
    if n == 0 or model.k == 0 or model.bounded:
        return n, None
    nq, nv = model.nq, model.nv
    q_size = 1.0 + np.abs(y[:n, :nq]).max(axis=1, initial=0.0)
    v_size = 1.0 + np.abs(y[:n, nq : nq + nv]).max(axis=1, initial=0.0)
    g_off = ~(np.abs(g[:n]) <= tol * q_size[:, None])
    Phi_off = ~(np.abs(Phi[:n]) <= tol * v_size[:, None])
    samples = np.flatnonzero((g_off | Phi_off).any(axis=1))
    if not samples.size:
        return n, None
    i = int(samples[0])
    relative = np.where(g_off[i], np.abs(g[i]) / q_size[i], np.abs(Phi[i]) / v_size[i])
    row = int(np.argmax(np.nan_to_num(np.where(g_off[i] | Phi_off[i], relative, -1.0), nan=np.inf)))
    what, value, size = ("g(q, t)", g[i, row], q_size[i]) if g_off[i, row] else ("Φ(q, v, t)", Phi[i, row], v_size[i])
    name = model.row_names[row]
    norm = "‖q‖∞" if what == "g(q, t)" else "‖v‖∞"
    return i + 1, DriftError(
        f"the motion left the constraint {name!r} at t={t[i]:.6g}: {what} = {value:.3g} exceeds drift_tol·(1 + "
        f"{norm}) = {tol * size:.3g} (samples after it are dropped); {ADVICE}",
        t=float(t[i]),
        constraint=name,
        residual=float(value),
    )
