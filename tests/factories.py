"""Problem factories shared by the tests."""

from __future__ import annotations

import numpy as np

import gausspp as gp


def random_spd(rng: np.random.Generator, n: int, log10_cond: float) -> np.ndarray:
    """A symmetric positive definite matrix with condition number 10**log10_cond."""
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    eig = np.logspace(0.0, log10_cond, n)
    rng.shuffle(eig)
    A = (Q * eig) @ Q.T
    return 0.5 * (A + A.T)


def double_pendulum(m1: float = 1.3, m2: float = 0.7, l1: float = 0.9, l2: float = 1.4) -> gp.Lagrangian:
    """Planar double pendulum in absolute angles, no forces (so f = −h)."""
    import casadi as ca

    def T(q, v, t):
        return (
            0.5 * (m1 + m2) * l1**2 * v[0] ** 2
            + 0.5 * m2 * l2**2 * v[1] ** 2
            + m2 * l1 * l2 * v[0] * v[1] * ca.cos(q[0] - q[1])
        )

    return gp.Lagrangian(n=2, T=T)


def kane_system(damping: float = 0.0) -> tuple:
    """A pendulum's sympy ``KanesMethod`` in its angle from the downward x axis, and its constants ``(m, l, g)``:
    gravity as a load on the bob, ``damping`` a torque ``−c u`` on the rod (needs sympy)."""
    import sympy as sm
    import sympy.physics.mechanics as me

    q, u = me.dynamicsymbols("q u")
    m, l, gravity = sm.symbols("m l g")
    frame = me.ReferenceFrame("N")
    rod = frame.orientnew("R", "Axis", (q, frame.z))
    rod.set_ang_vel(frame, u * frame.z)
    origin = me.Point("O")
    origin.set_vel(frame, 0)
    bob = origin.locatenew("P", l * rod.x)
    bob.v2pt_theory(origin, frame, rod)
    kane = me.KanesMethod(frame, q_ind=[q], u_ind=[u], kd_eqs=[q.diff() - u])
    loads = [(bob, m * gravity * frame.x), (rod, -damping * u * frame.z)]
    kane.kanes_equations([me.Particle("p", bob, m)], loads)
    return kane, (m, l, gravity)


def kane_pendulum(g: float = 9.81, damping: float = 0.0) -> gp.SympyModel:
    """A pendulum (unit mass, unit length) in its angle from the downward x axis, built with sympy's KanesMethod
    (:func:`kane_system`); no constraint (needs sympy)."""
    kane, (m, l, gravity) = kane_system(damping)
    return gp.from_sympy(kane, parameters={m: 1.0, l: 1.0, gravity: g})
