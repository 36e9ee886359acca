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
from ..model.reach_sizes import reach_sizes
from ..model.run_scales import ATOL_SHARE
from ..step.bound import Bound
from ..step.servo_reach import Reach, ReachSizes, find_reach, outputs
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
    work_reaction, work_forces : (N,) arrays
        The actuators' work ``∫ v·D u dt`` and the non-conservative forces' ``∫ v·F dt`` since ``t0``, integrated with
        the motion (to its tolerance, not by a quadrature of the samples).
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
    work_reaction: np.ndarray
    work_forces: np.ndarray
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


def consistent_start(
    hidden: ca.SX, reach: Reach, t0: float, z_guess: np.ndarray, size: np.ndarray, tol: float = 1e-12
) -> np.ndarray:
    """The extended state nearest ``z_guess`` on the hidden constraints (Gauss–Newton, minimum-norm steps); each
    hidden row's residual is judged against the terms it adds up, ``Σ_j |∂c_i/∂z_j| max(|z_j|, size_j)``."""
    e = reach.extended
    c_of = ca.Function("hidden", [e.t, e.z], [hidden, ca.jacobian(hidden, e.z)])
    z = np.array(z_guess, float)
    for _ in range(50):
        c, J = (np.array(x, float) for x in c_of(t0, z))
        c = c.ravel()
        scale = np.abs(J) @ np.maximum(np.abs(z), size)
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
    pole: float | None = None,
    sizes: ReachSizes | None = None,
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
        DOP853's tolerances; ``atol`` may also be one per component of ``(q, v)`` (``gp.simulate`` passes ``rtol``
        times each component's size: :func:`gausspp.model.run_scales.RunScales.atol`), and then the actuators'
        chain states take ``rtol`` times a tenth of their sizes (:class:`~gausspp.step.servo_reach.ReachSizes`).
    record : array of times, optional
        Where to sample (default: 401 samples).
    pole : float, optional
        ``p`` of (1), in 1/time: how fast an integration error along the constraint decays. Default ``1/τ``, the
        motion's time scale (:mod:`gausspp.model.reach_sizes`): the same feedback in any units.
    sizes : ReachSizes, optional
        The sizes the reach test weighs sensitivities by; default the run's
        (:func:`gausspp.model.reach_sizes.reach_sizes` over ``t_end − t0``).
    """
    t_end = float(t_end)
    if not t_end > t0:
        raise InputError(f"t_end must be after t0={t0}, got {t_end}")
    t, q, v, _ = model.checked_state(t0, q0, v0, None)
    sizes = sizes if sizes is not None else reach_sizes(model, t, q, v, t_end - t)
    pole = positive("pole", pole) if pole is not None else 1.0 / sizes.time
    reach = find_reach(model, t, q, v, sizes=sizes)
    e = reach.extended
    w, hidden = feedback(reach, pole)
    zdot = ca.substitute(e.zdot, e.w, w)
    force = ca.substitute(e.force, e.w, w)
    start = np.concatenate([q, v, np.zeros(sum(reach.extended.chains))])
    z0 = np.concatenate([consistent_start(hidden, reach, t, start, sizes.state(e.chains)), [0.0, 0.0]])
    powers = _powers(model, force)
    rhs = Bound(ca.Function("servo_rhs", [e.t, e.z], ca.cse([ca.vertcat(zdot, ca.substitute(powers, e.w, w))])))
    evaluations = 0

    def f(time: float, z: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        rhs.args[0][0], rhs.args[1][:] = time, z[:-2]
        rhs.eval()
        return rhs.res[0].copy()

    grid = np.linspace(t, t_end, 401) if record is None else record_times("simulate_servo", record, t, t_end)
    chain_atol = ATOL_SHARE * rtol * sizes.state(e.chains)[model.nq + model.nv :]
    sol = solve_ivp(
        f, (t, t_end), z0, method="DOP853", rtol=rtol, atol=_atol(atol, chain_atol, z0.size - 2), t_eval=grid
    )
    works, Z = sol.y[-2:].T, sol.y[:-2].T
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
        work_reaction=works[:, 0],
        work_forces=works[:, 1],
        status=status,
        message=message,
        rhs_evaluations=evaluations,
    )


def _powers(model: Model, force: ca.SX) -> ca.SX:
    """The actuators' power ``v·D u`` and the non-conservative forces' ``v·F`` in terms of the extended state."""
    p, mech = model.expressions, model.mechanism
    stab = model.inputs[4]
    D = ca.substitute(p.D, stab, ca.SX.zeros(stab.shape))
    forces = ca.dot(mech.v, mech.F_nc) if mech.F_nc is not None else ca.SX(0)
    return ca.vertcat(ca.dot(mech.v, D @ force), forces)


def _atol(atol: Any, chain_atol: np.ndarray, size: int) -> np.ndarray:
    """DOP853's absolute tolerance on the extended state: ``atol`` on each of ``(q, v)`` and ``chain_atol`` on the
    chain states (a force and its derivatives, sized by the run), or one number for all; none on the two works:
    they ride on the steps the motion takes (a quadrature of order 8), and their unit is another."""
    if np.ndim(atol):
        state = np.concatenate([np.asarray(atol, float), chain_atol])
    else:
        state = np.full(size, float(atol))
    return np.concatenate([state, [np.inf, np.inf]])
