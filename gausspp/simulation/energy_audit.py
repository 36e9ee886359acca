"""Success means within tolerance, for the energy too: the recorded energy balance checked before a run is a success.

Where the model knows its energy ``E`` and the power of its non-conservative forces, and neither its energy nor
its mass matrix depends on time explicitly, every motion keeps ``E − E₀ = W_R + W_F``: the work of the reactions
(the constraints', the actuators', the impacts') and of the applied forces, both integrated along the run. A
step too long for the motion breaks that balance even where no constraint shows it (a model without rows, a
fast spin). :func:`energy_audit` compares ``|E − E₀ − W_R − W_F|`` at every sample with
``ENERGY_SHARE · drift_tol`` times the energy scale reached — the largest kinetic energy plus the largest
exchanges ``|E − E₀| + |W_R| + |W_F|`` so far, and at least those of the run's first tenth — so a method's own
error (``O(dt⁴)`` for ``rk4``, ``O(dt)`` oscillating for symplectic Euler, ``O(rtol)`` adaptive) passes and a
motion that gained or lost a tenth of its energy scale does not. The first sample beyond it ends the run with a
:class:`~gausspp.DriftError` (``constraint="energy balance"``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import DriftError
from ..model.model import Model
from ..model.run_scales import RunScales, energy_scale, scales_at_first
from ..workspace import workspace

#: The balance may be off by this times ``drift_tol`` of the energy scale (default: a tenth of it).
ENERGY_SHARE = 100.0
#: A state grown by more than this times the initial one is no error of a step but a motion that diverged.
DIVERGED = 1e6
#: A sample is judged against the energy scale reached so far, and at least against that of the run's first
#: ``1/EARLY``: a first-order method's error is O(1) of its first steps' exchange, O(dt) of the motion's.
EARLY = 10
#: Kinetic energies are evaluated at up to this many samples, spread over the run (the scale needs no more).
KINETIC_SAMPLES = 64


def closes(model: Model) -> bool:
    """Whether the model's energy balance is known to close: energy and forces' power known, no explicit time."""
    mech = model.mechanism
    if mech.energy is None or not model.has_force_power:
        return False
    return workspace(model).get(
        ("energy balance closes",),
        lambda: not (ca.depends_on(ca.SX(mech.energy), mech.t) or ca.depends_on(ca.SX(mech.A), mech.t)),
    )


def energy_audit(
    model: Model,
    t: np.ndarray,
    y: np.ndarray,
    energy: np.ndarray,
    tol: float,
    n: int,
    scales: RunScales | None = None,
) -> tuple[int, DriftError | None]:
    """The samples to keep of the first ``n`` and the failure, if the energy balance of ``(t, y)`` (``y``'s last two
    columns the works ``W_R, W_F``; ``energy`` recorded beside) leaves ``ENERGY_SHARE·tol`` of the energy scale
    reached (at least that of the run's first tenth), above its round-off floor
    (:func:`~gausspp.model.run_scales.energy_scale`)."""
    if n < 2 or not closes(model):
        return n, None
    balance = (energy[:n] - energy[0]) - (y[:n, -2] - y[0, -2]) - (y[:n, -1] - y[0, -1])
    early = max(1, n // EARLY)  # every sample is judged against at least the scale of the run's first tenth
    off = beyond(model, scales or scales_at_first(model, t, y), t[:n], y[:n], energy[:n], balance, tol, early)
    if off is None:
        return n, None
    i, scale_i = off
    size = np.abs(y[: i + 1, : model.nq + model.nv])
    what = "diverged" if not size[-1].max() <= DIVERGED * (1.0 + size[0].max()) else "left its energy balance"
    return i + 1, DriftError(
        f"the motion {what} at t={t[i]:.6g}: E − E₀ − W_reaction − W_forces = {balance[i]:.3g} "
        f"exceeds {ENERGY_SHARE:g}·drift_tol of the run's energy scale {scale_i:.3g} (samples after it are dropped); "
        "a shorter step (dt) or tighter rtol/atol follows the motion; a larger drift_tol accepts this error",
        t=float(t[i]),
        constraint="energy balance",
        residual=float(balance[i]),
    )


def beyond(
    model: Model,
    scales: RunScales,
    t: np.ndarray,
    y: np.ndarray,
    energy: np.ndarray,
    balance: np.ndarray,
    tol: float,
    early: int | None,
) -> tuple[int, float] | None:
    """The first sample whose ``|balance|`` exceeds ``ENERGY_SHARE·tol`` of the energy scale and its round-off
    floor, with that scale; ``None`` if none does (NaN counts as beyond). ``early``: judge each sample against at
    least the scale of sample ``early`` (``None``: against the whole run's)."""
    n = t.size
    kinetic = kinetic_energies(model, t, y, n)
    size, floor = energy_scale(model, scales, t, energy, kinetic, (y[:, -2], y[:, -1]), early)
    limit = np.maximum(ENERGY_SHARE * tol * size, floor)
    off = np.flatnonzero(~(np.abs(balance) <= limit))
    if not off.size:
        return None
    i = int(off[0])
    return i, float(size[i])


def kinetic_energies(model: Model, t: np.ndarray, y: np.ndarray, n: int) -> np.ndarray:
    """``½ vᵀ A v`` at up to :data:`KINETIC_SAMPLES` samples of the first ``n`` (0 at the others): one call of the
    mapped kinetic energy (kept in the model's workspace)."""
    nq, nv = model.nq, model.nv
    kinetic = np.zeros(n)
    idx = np.unique(np.linspace(0, n - 1, min(n, KINETIC_SAMPLES)).astype(int))
    states = np.zeros((nq + nv + 1, KINETIC_SAMPLES))
    states[0, : idx.size] = t[idx]
    states[1:, : idx.size] = y[idx, : nq + nv].T
    states[:, idx.size :] = states[:, :1]
    good = np.isfinite(states).all(axis=0)
    states[:, ~good] = 0.0
    values = np.array(_kinetic_function(model)(states)).ravel()
    kinetic[idx] = np.where(good[: idx.size], values[: idx.size], 0.0)
    return np.nan_to_num(kinetic, nan=0.0, posinf=0.0)


def _kinetic_function(model: Model) -> ca.Function:
    """``[t; q; v]`` (one column per sample, :data:`KINETIC_SAMPLES` of them) ``↦ ½ vᵀ A(q, t) v`` per column."""

    def build() -> ca.Function:
        mech = model.mechanism
        state = ca.vertcat(mech.t, mech.q, mech.v)
        one = ca.Function("kinetic", [state], [0.5 * ca.dot(mech.v, ca.mtimes(mech.A, mech.v))])
        return one.map(KINETIC_SAMPLES)

    return workspace(model).get(("kinetic energy, mapped",), build)
