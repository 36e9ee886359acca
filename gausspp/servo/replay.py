"""The open-loop replay: the free mechanism under the forces index reduction returned, and nothing else."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

from ..errors import InputError
from ..model.model import Model, model_argument
from ..step.bound import Bound
from ..step.servo_reach import outputs
from ..validation import positive, short
from .index_reduction import ServoTrajectory


@dataclass(frozen=True)
class Replay:
    """The replayed motion at the servo trajectory's times, and how far it stays from the constraint."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    constraint: np.ndarray  # y along the replay: zero on the path


def replay(model: Model, traj: ServoTrajectory, rtol: float = 1e-12, atol: float = 1e-13) -> Replay:
    """Integrate ``A v̇ = f + D u(t)``, ``q̇ = K(q, v, t)`` from the trajectory's first state with the forces
    ``u(t)`` interpolated (cubic splines through its samples) — no constraint, no feedback: if the forces are
    right, the motion follows the path by itself (up to the interpolation and the integration's errors)."""
    model_argument("replay", model)
    if not all(hasattr(traj, name) for name in ("t", "q", "v", "forces")):
        raise InputError(f"replay: traj must be the ServoTrajectory of gp.simulate_servo, got {short(traj)}")
    rtol = positive("rtol", rtol, hint=" (replay's relative tolerance)")
    atol = positive("atol", atol, zero_ok=True, hint=" (replay's absolute tolerance)")
    p = model.expressions
    t, q, v, lam, stab = model.inputs
    u = ca.SX.sym("u", model.m)
    zero = ca.SX.zeros(stab.shape)
    vdot = ca.solve(p.A, ca.substitute(p.f + p.r0 + p.D @ u, stab, zero))
    qdot = p.qdot if p.qdot is not None else v
    rhs = Bound(ca.Function("free", [t, q, v, u], [ca.vertcat(qdot, vdot)]))
    forces = CubicSpline(traj.t, traj.forces, axis=0)
    nq = model.nq

    def f(time: float, y: np.ndarray) -> np.ndarray:
        rhs.args[0][0], rhs.args[1][:], rhs.args[2][:], rhs.args[3][:] = time, y[:nq], y[nq:], forces(time)
        rhs.eval()
        return rhs.res[0].copy()

    y0 = np.concatenate([traj.q[0], traj.v[0]])
    sol = solve_ivp(f, (traj.t[0], traj.t[-1]), y0, method="DOP853", rtol=rtol, atol=atol, t_eval=traj.t)
    Q, V = sol.y[:nq].T, sol.y[nq:].T
    y_of = ca.Function("y", [t, q, v], [outputs(model)]).map(sol.t.size)
    return Replay(sol.t, Q, V, np.array(y_of(sol.t[None, :], Q.T, V.T), float).T)
