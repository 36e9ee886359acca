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
