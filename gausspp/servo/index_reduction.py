"""Index reduction: motions the one-step formula cannot reach, by index reduction (docs/theory.md, servo-constraints).

With the relative degrees ``rᵢ`` and the dynamic extension of :mod:`gausspp.step.servo_reach`, the servo problem
becomes: the extended state ``z = (q, v, ξ)`` moves by ``ż = F(z, w, t)`` and the inputs ``w`` are those that make

    yᵢ⁽ʳⁱ⁾ + Σⱼ aᵢⱼ yᵢ⁽ʲ⁾ = 0,      aᵢⱼ = C(rᵢ, j) pʳⁱ⁻ʲ                                   (1)

— the constraint differentiated as often as the actuators need (``y⁽ʳ⁾ = Y(z, t) + B(z, t) w`` with ``B``
nonsingular), with every lower derivative fed back through the polynomial ``(s + p)ʳ`` (all roots at ``−p``):
Baumgarte's idea taken to the order ``r``, so that the round-off and truncation errors of the integration decay
instead of drifting. The start is made consistent first: the hidden constraints ``yᵢ⁽ʲ⁾(z, t₀) = 0``,
``j < rᵢ``, are solved for ``z`` nearest the given state (Gauss–Newton with minimum-norm corrections) — for a
flat system (the crane, the spring chain) they fix the state entirely, forces included.

The forces come out with the motion: the extended actuators' are states (``ξ``), the others are inputs ``w``.
The closed loop is one compiled casadi function; scipy's DOP853 integrates it.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb
from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ..errors import InputError, IntegrationError
from ..model.model import Model
from ..step.bound import Bound
from ..step.servo_reach import Reach, find_reach, outputs
from ..validation import positive, record_times


@dataclass(frozen=True)
class ServoTrajectory:
    """A motion along a servo-constraint and the actuator forces that make it (:func:`simulate_servo`).

    Attributes
    ----------
    t : (N,) array
    q, v : (N, nq), (N, nv) arrays
    forces : (N, m) array
        Each actuator's force (its multiplier ``λ`` along its row of ``M``).
    constraint : (N, k) array
        The constrained quantities ``y`` (``g(q, t)`` or ``Φ``): zero along the prescribed path.
    degrees, unextended : tuple of int
        The rows' relative degrees with the integrators index reduction added, and without.
    chains : tuple of int
        Integrators put in front of each actuator (the dynamic extension).
    index : int
        The servo DAE's differentiation index, ``max rᵢ + 1``.
    status, message : str
        ``"success"``, or ``"failed"`` and why (the samples are those computed until then).
    rhs_evaluations : int
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    forces: np.ndarray
    constraint: np.ndarray
    degrees: tuple[int, ...]
    unextended: tuple[int, ...]
    chains: tuple[int, ...]
    index: int
    status: str
    message: str
    rhs_evaluations: int


def feedback(reach: Reach, p: float) -> tuple[ca.SX, ca.SX]:
    """The inputs ``w(z, t)`` of (1), and the hidden constraints ``yᵢ⁽ʲ⁾``, ``j < rᵢ``, stacked."""
    e = reach.extended
    top, lower = [], []
    for chain in reach.derivatives:
        r = len(chain) - 1
        top.append(chain[-1] + sum(comb(r, j) * p ** (r - j) * chain[j] for j in range(r)))
        lower.extend(chain[:-1])
    top_v = ca.vertcat(*top)
    B = ca.jacobian(top_v, e.w)
    Y = ca.substitute(top_v, e.w, ca.SX.zeros(e.w.shape))
    return ca.solve(B, -Y), ca.vertcat(*lower)


def consistent_start(hidden: ca.SX, reach: Reach, t0: float, z_guess: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    """The extended state nearest ``z_guess`` on the hidden constraints (Gauss–Newton, minimum-norm steps)."""
    e = reach.extended
    c_of = ca.Function("hidden", [e.t, e.z], [hidden, ca.jacobian(hidden, e.z)])
    z = np.array(z_guess, float)
    for _ in range(50):
        c, J = (np.array(x, float) for x in c_of(t0, z))
        c = c.ravel()
        weight = np.abs(J).sum(axis=1)  # each hidden row against the size of the components it depends on
        scale = 1.0 + np.abs(J) @ np.abs(z) / np.where(weight > 0, weight, 1.0)
        if np.all(np.abs(c) <= tol * scale):
            return z
        z = z - np.linalg.lstsq(J, c, rcond=None)[0]
    raise InputError(
        f"the initial state cannot be brought onto the servo's hidden constraints at t={t0:g} (the constraint and "
        f"its first {max(reach.degrees) - 1} derivatives; residual {np.abs(c).max():.3g}): start nearer the path"
    )


def simulate_servo(
    model: Model,
    q0: Any,
    v0: Any,
    t_end: float,
    *,
    t0: float = 0.0,
    rtol: float = 1e-11,
    atol: Any = 1e-12,
    record: Any = None,
    pole: float = 1.0,
) -> ServoTrajectory:
    """Follow the model's servo-constraints with its actuators, whatever their reach (module docstring).

    Parameters
    ----------
    model : Model
        Constraints realized by actuator forces (:class:`~gausspp.Force`), as many actuators as rows, no λ state.
    q0, v0 : arrays
        A start near the path; it is made consistent with the hidden constraints (and the forces found).
    t_end : float
    rtol, atol : float
        DOP853's tolerances; ``atol`` may also be one per component of ``(q, v)`` followed by one for the actuators'
        chain states (``gp.simulate`` passes ``rtol`` times each component's size:
        :func:`gausspp.simulation.scales.RunScales.atol`).
    record : array of times, optional
        Where to sample (default: 401 samples).
    pole : float
        ``p`` of (1), in 1/s: how fast an integration error along the constraint decays.
    """
    t_end, pole = float(t_end), positive("pole", pole)
    if not t_end > t0:
        raise InputError(f"t_end must be after t0={t0}, got {t_end}")
    t, q, v, _ = model.checked_state(t0, q0, v0, None)
    reach = find_reach(model, t, q, v)
    e = reach.extended
    w, hidden = feedback(reach, pole)
    zdot = ca.substitute(e.zdot, e.w, w)
    force = ca.substitute(e.force, e.w, w)
    z0 = consistent_start(hidden, reach, t, np.concatenate([q, v, np.zeros(sum(reach.extended.chains))]))
    rhs = Bound(ca.Function("servo_rhs", [e.t, e.z], ca.cse([zdot])))
    evaluations = 0

    def f(time: float, z: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        rhs.args[0][0], rhs.args[1][:] = time, z
        rhs.eval()
        return rhs.res[0].copy()

    grid = np.linspace(t, t_end, 401) if record is None else record_times("simulate_servo", record, t, t_end)
    if np.ndim(atol):  # (q, v) and one value for the chain states
        atol = np.concatenate(
            [np.asarray(atol, float)[:-1], np.full(z0.size - np.size(atol) + 1, np.asarray(atol)[-1])]
        )
    sol = solve_ivp(f, (t, t_end), z0, method="DOP853", rtol=rtol, atol=atol, t_eval=grid)
    Z = sol.y.T
    samples = ca.Function("samples", [e.t, e.z], [force, outputs(model)])  # z starts with the model's own q, v
    forces, ys = (np.array(x, float) for x in samples.map(Z.shape[0])(sol.t[None, :], Z.T))
    nq, nv = model.nq, model.nv
    status, message = ("success", "") if sol.success else ("failed", str(sol.message))
    if not sol.success and Z.shape[0] == 0:
        raise IntegrationError(f"index reduction failed at once: {sol.message}")
    return ServoTrajectory(
        t=sol.t,
        q=Z[:, :nq],
        v=Z[:, nq : nq + nv],
        forces=forces.T,
        constraint=ys.T,
        degrees=reach.degrees,
        unextended=reach.unextended,
        chains=reach.extended.chains,
        index=reach.index,
        status=status,
        message=message,
        rhs_evaluations=evaluations,
    )
