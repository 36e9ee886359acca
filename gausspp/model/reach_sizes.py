"""The sizes the reach test of servo-constraints weighs its sensitivities by, from a run's scales.

:func:`gausspp.step.servo_reach.find_reach` asks whether an actuator's force appears in a derivative of the
constraint: ``|∂h/∂w| S_w`` against ``|∂h/∂z_j| S_z,j``. For that comparison to mean the same in any units every
size must be a physical one, read from the machine (:mod:`gausspp.model.run_scales`):

* ``S_q``, ``S_v``: the run's sizes of the coordinates and velocities;
* the time scale ``τ``, with ``τ² = Σ_j A_jj S_q,j² / Σ_j A_jj S_v,j²`` (both sums in energy·time² and energy,
  whatever each component's unit: a length and an angle are weighed by the inertia that moves with them);
* each actuator's force ``S_u,a = Ẽ / Σ_j |D_ja| S_q,j`` with ``Ẽ = ½ Σ_j A_jj S_v,j²``: the force whose work over
  the coordinates' sizes is the machine's kinetic energy at its sizes;
* the ``j``-th derivative of a force ``S_u / τʲ``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..step.servo_reach import ReachSizes, state_sizes
from .run_scales import RunScales, run_scales, structure

if TYPE_CHECKING:
    from .model import Model


def reach_sizes(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, horizon: float, scales: RunScales | None = None
) -> ReachSizes:
    """The sizes of a run of ``model`` from ``(t, q, v)`` over ``horizon`` (module docstring). A machine at rest with
    nothing to move it has no sizes of its own: then each coordinate is sized by its value (1 where it is zero, in
    whatever unit: the reach of a linear machine does not depend on it), the time by the horizon, and the speeds and
    forces follow from those as above — consistent in any units. ``scales``: the run's, where the caller has read
    them already."""
    if scales is None:
        scales = run_scales(model, t, q, v, np.zeros(model.n_lam), horizon)
    data = model.evaluate_data(t, q, v, np.zeros(model.n_lam))
    mass = np.abs(np.diag(np.asarray(data.A, float)))
    D = np.abs(np.asarray(data.D, float))
    coupling = structure(model)
    sizes = _consistent(mass, D, coupling.velocity_sized(scales.q), scales.q, scales.v)
    if sizes is None and horizon > 0:  # nothing moves: the run's horizon is the one time scale
        size_q = np.where(np.abs(q) > 0, np.abs(q), 1.0)
        size_dq = coupling.velocity_sized(size_q)
        sizes = _consistent(mass, D, size_dq, size_q, size_dq / horizon)
    return sizes if sizes is not None else state_sizes(model, q, v)


def _consistent(
    mass: np.ndarray, D: np.ndarray, size_dq: np.ndarray, size_q: np.ndarray, size_v: np.ndarray
) -> ReachSizes | None:
    """The sizes from the coordinates' (``size_dq``: along each velocity component) and the velocities': the time
    scale and the actuators' forces (module docstring); ``None`` where they do not give them."""
    momentum_time = float(mass @ size_dq**2)
    energy = 0.5 * float(mass @ size_v**2)
    lever = D.T @ size_dq if D.size else np.zeros(D.shape[1] if D.ndim == 2 else 0)
    usable = np.isfinite(momentum_time) and np.isfinite(energy) and momentum_time > 0 and energy > 0
    if not (usable and np.all(np.isfinite(lever)) and np.all(lever > 0)):
        return None
    return ReachSizes(size_q, size_v, energy / lever, float(np.sqrt(momentum_time / (2.0 * energy))))
