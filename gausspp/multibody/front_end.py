"""The bodies of a multibody system as one mechanism (a :class:`gausspp.Mechanism` front end).

The state stacks the bodies' coordinates and velocities (:mod:`.bodies`). The kinetic-energy matrix is constant
and block diagonal — ``diag(m, m, I)`` per planar body, ``diag(m, m, m, J)`` per spatial one — so the step takes
the sparse route on large systems. The generalized force of a body is its weight and applied force on the centre of
mass and, for a spatial body, the applied torque minus the gyroscopic term ``ω × Jω`` (Euler's equations in body
axes). The energy is ``T + V`` with the weight's potential ``V = −m g·r``; applied loads are non-conservative (their
power closes the energy balance).
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np

from ..errors import ShapeError
from ..model.mechanism import Mechanism, QuaternionCoordinates, quaternion_rate
from ..model.symbolic import evaluate
from .bodies import Body


class Bodies(QuaternionCoordinates, Mechanism):
    """Planar or spatial rigid bodies in maximal coordinates under ``gravity`` (module docstring)."""

    def __init__(self, bodies: Sequence[Body], gravity: np.ndarray) -> None:
        self.bodies = list(bodies)
        nq, nv = sum(b.nq for b in self.bodies), sum(b.nv for b in self.bodies)
        self._symbols(nq, nv)
        q, v = self.q, self.v
        g = ca.DM(np.asarray(gravity, float))
        blocks, forces, loads, qdots, kinetic, potential = [], [], [], [], ca.SX(0), ca.SX(0)
        for b in self.bodies:
            c, w = q[b.q_start : b.q_start + b.nq], v[b.v_start : b.v_start + b.nv]
            m = b.mass
            if b.planar:
                blocks.append(ca.DM(np.diag([m, m, b.inertia[0, 0]])))
                applied = self._load(b, w, 3)
                forces.append(ca.vertcat(m * g, 0) + applied)
                qdots.append(w)
                kinetic += 0.5 * (m * ca.dot(w[:2], w[:2]) + b.inertia[0, 0] * w[2] ** 2)
                potential -= m * ca.dot(g, c[:2])
            else:
                J = ca.DM(b.inertia)
                blocks.append(ca.diagcat(ca.DM(np.eye(3) * m), J))
                applied = self._load(b, w, 6)
                omega = w[3:6]
                forces.append(ca.vertcat(m * g, -ca.cross(omega, J @ omega)) + applied)
                p = c[3:7]
                qdots.append(ca.vertcat(w[:3], quaternion_rate(p, omega)))
                kinetic += 0.5 * (m * ca.dot(w[:3], w[:3]) + ca.dot(omega, J @ omega))
                potential -= m * ca.dot(g, c[:3])
            loads.append(applied)
        self.A = ca.SX(ca.diagcat(*blocks)) if blocks else ca.SX(0, 0)
        self.f = ca.vertcat(*forces)
        self.qdot = ca.vertcat(*qdots)
        self.energy = kinetic + potential
        self.F_nc = ca.vertcat(*loads)
        self.coordinate_names = tuple(n for b in self.bodies for n in b.coordinate_names())
        self.velocity_names = tuple(n for b in self.bodies for n in b.velocity_names())
        self._quaternions = [slice(b.q_start + 3, b.q_start + 7) for b in self.bodies if not b.planar]

    def _load(self, b: Body, w: ca.SX, n: int) -> ca.SX:
        """The body's applied force and torque as a generalized force (``n`` entries): ``load(r, R, v, t)``."""
        if b.load is None:
            return ca.SX.zeros(n)
        r, R = b.parts(self.q)
        return evaluate(b.load, (r, R, w, self.t), (n, 1), f"body {b.name!r}: load(r, R, v, t)")

    def variation_matrix(self) -> ca.SX:
        """``δω = η̇ + ω × η`` on each spatial body's rotation, zero elsewhere."""
        C = ca.SX.zeros(self.nv, self.nv)
        for b in self.bodies:
            if not b.planar:
                w = self.v[b.v_start + 3 : b.v_start + 6]
                i = b.v_start + 3
                C[i : i + 3, i : i + 3] = ca.skew(w)
        return C

    def lagrange_rows(self, N: ca.SX) -> ca.SX:
        """``[N_i]``: Lagrange's derivative in the planar bodies' coordinates and the spatial bodies' centres,
        Euler–Poincaré's ``d/dt ∂N/∂ω + ω × ∂N/∂ω`` in their angular velocities (``N`` must not depend on their
        orientations, as for :class:`gausspp.RigidBody`)."""
        for s in self._quaternions:
            if ca.depends_on(N, self.q[s]):
                raise ShapeError(
                    "Multibody: a servo-constraint's N must not depend on a spatial body's orientation (the "
                    "Euler–Poincaré form used here holds for N independent of it); use an ideal realization"
                )
        q, v, t = self.q, self.v, self.t
        Nv = ca.jacobian(N, v)
        rows = []
        for i in range(N.numel()):
            p = Nv[i, :].T
            row = ca.jacobian(p, q) @ self.qdot + ca.jacobian(p, t)
            grad = ca.jacobian(N[i], q).T
            for b in self.bodies:
                for k in range(3):  # the coordinates whose rates are velocities: (x, y, θ) or (x, y, z)
                    row[b.v_start + k] -= grad[b.q_start + k]
                if not b.planar:
                    j = b.v_start + 3
                    row[j : j + 3] += ca.cross(v[j : j + 3], p[j : j + 3])
            rows.append(row.T)
        return ca.vertcat(*rows) if rows else ca.SX(0, self.nv)
