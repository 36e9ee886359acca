"""Model front ends: where the mechanical system's ``A``, ``F − h`` and kinematics come from.

A front end turns a user's description into symbolic casadi expressions, once:

* ``A(q, t)`` — the kinetic-energy matrix ``∂²T/∂v²`` (docs/theory.md §1),
* ``f(q, v, t) = F − h`` — applied forces minus the velocity terms of ``[T] = A ẍ + h``,
* ``q̇ = K(q, v, t)`` — the kinematics (identity for generalized coordinates,
  quaternion kinematics for a rigid body in body angular velocity),
* the Lagrange derivative ``[N]`` of any function affine in the velocities.

Three front ends: :class:`Lagrangian` (symbolic ``T`` and ``F``), :class:`RigidBody`
(body angular velocity ``ω``, Euler–Poincaré operator) and :class:`MassMatrix`
(explicit ``A(q, t) q̈ = f(q, v, t)``, as multibody codes and test sets give them).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, ShapeError
from .symbolic import check_constant_matrix, evaluate, require_affine_in

Expr = Callable[..., Any]


class Mechanism(ABC):
    """A mechanical system without constraints: the contract every front end fulfils.

    Subclasses set, in their ``__init__``:

    1. ``q``, ``v``, ``t`` — casadi ``SX`` symbols of sizes ``nq``, ``nv``, 1;
    2. ``A`` — ``(nv, nv)`` kinetic-energy matrix, symmetric positive definite;
    3. ``f`` — ``(nv,)`` generalized force minus velocity terms, ``F − h``;
    4. ``qdot`` — ``(nq,)`` kinematics ``q̇ = K(q, v, t)``;
    5. ``energy`` — total energy expression, or ``None`` if not known;
    6. ``F_nc`` — ``(nv,)`` non-conservative applied forces (their power ``v·F_nc`` closes the
       energy balance ``dE/dt = v·(F_nc + R)``), or ``None`` if not known;

    and implement :meth:`lagrange_rows`, the Lagrange derivative of an affine function.
    Override :meth:`normalize` where ``q`` lives on a manifold (unit quaternions). A front end that
    knows its coordinates' and velocities' names sets ``coordinate_names`` / ``velocity_names``
    (tuples of ``nq`` / ``nv`` strings); results carry them (:class:`gausspp.Trajectory`).
    """

    q: ca.SX
    v: ca.SX
    t: ca.SX
    A: ca.SX
    f: ca.SX
    qdot: ca.SX
    energy: ca.SX | None
    F_nc: ca.SX | None = None
    symmetric_by_construction: bool = True
    coordinate_names: tuple[str, ...] | None = None
    velocity_names: tuple[str, ...] | None = None

    def normalize(self, q: ca.SX) -> ca.SX:
        """Bring ``q`` back onto the configuration manifold (identity for coordinates in Rⁿ)."""
        return q

    def normalize_array(self, q: np.ndarray) -> np.ndarray:
        """:meth:`normalize` on numbers: one configuration ``(nq,)``, or one per row ``(N, nq)``."""
        return q

    def variation_matrix(self) -> ca.SX:
        """``C`` in ``δv = η̇ + C η`` for a variation ``η`` of a path (zero for generalized coordinates)."""
        return ca.SX.zeros(self.nv, self.nv)

    @property
    def nq(self) -> int:
        """Number of configuration coordinates."""
        return int(self.q.numel())

    @property
    def nv(self) -> int:
        """Number of velocities (the size of ``A`` and of an acceleration)."""
        return int(self.v.numel())

    @abstractmethod
    def lagrange_rows(self, N: ca.SX) -> ca.SX:
        """``[N_i]`` for each component of ``N`` (affine in ``v``), as rows of a ``(k, nv)`` SX.

        ``[f] = d/dt ∂f/∂v − ∂f/∂q`` in generalized coordinates; because ``N`` is affine in
        ``v`` the result contains no acceleration (docs/theory.md §2).
        """

    def lagrange_derivative(self, N: Expr) -> Callable[[Any, Any, float], np.ndarray]:
        """Compile ``[N]`` for a callable ``N(q, v, t)`` affine in velocities.

        Returns a function ``(q, v, t) -> (k, nv) array`` whose row ``i`` is ``[N_i]``.
        """
        expr = evaluate(N, (self.q, self.v, self.t), (None, 1), "N(q, v, t)")
        require_affine_in(expr, self.v, "N(q, v, t)")
        fn = ca.Function("lagrange_N", [self.q, self.v, self.t], [self.lagrange_rows(expr)])

        def call(q: Any, v: Any, t: float = 0.0) -> np.ndarray:
            return np.array(fn(np.asarray(q, float), np.asarray(v, float), float(t)))

        return call

    def _symbols(self, nq: int, nv: int) -> None:
        self.q = ca.SX.sym("q", nq)
        self.v = ca.SX.sym("v", nv)
        self.t = ca.SX.sym("t")


def _coordinate_lagrange_rows(N: ca.SX, q: ca.SX, v: ca.SX, t: ca.SX, qdot: ca.SX) -> ca.SX:
    Nv = ca.jacobian(N, v)
    rows = []
    for i in range(N.numel()):
        p = Nv[i, :].T
        dp_dt = ca.jacobian(p, q) @ qdot + ca.jacobian(p, t)
        rows.append((dp_dt - ca.jacobian(N[i], q).T).T)
    return ca.vertcat(*rows) if rows else ca.SX(0, v.numel())


#: The most coordinates a mechanism may have: its equations are built symbolically, one expression per entry
#: (a chain of 10 000 bodies already takes minutes); more is refused before the memory runs out.
MAX_COORDINATES = 10_000


def _check_n(n: int) -> int:
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n must be a positive integer, got {n!r}")
    if n > MAX_COORDINATES:
        raise InputError(
            f"n={n} coordinates: gausspp builds a mechanism's equations symbolically and takes at most "
            f"{MAX_COORDINATES} coordinates"
        )
    return int(n)


class Lagrangian(Mechanism):
    """Generalized coordinates from a symbolic kinetic energy.

    ``[T] = d/dt ∂T/∂v − ∂T/∂q = A q̈ + h`` with ``A = ∂²T/∂v²`` and
    ``h = (∂²T/∂v∂q) v + ∂²T/∂v∂t − ∂T/∂q``, both by automatic differentiation.

    Parameters
    ----------
    n : int
        Number of coordinates.
    T : callable ``(q, v, t) -> scalar``
        Kinetic energy, written with casadi operations.
    F : callable ``(q, v, t) -> (n,)``, optional
        Generalized (non-potential) forces.
    V : callable ``(q, t) -> scalar``, optional
        Potential energy; adds ``−∂V/∂q`` to the forces and ``V`` to the energy.
    """

    def __init__(self, n: int, T: Expr, F: Expr | None = None, V: Expr | None = None) -> None:
        n = _check_n(n)
        self._symbols(n, n)
        q, v, t = self.q, self.v, self.t
        kinetic = evaluate(T, (q, v, t), (1, 1), "T(q, v, t)")
        force = evaluate(F, (q, v, t), (n, 1), "F(q, v, t)") if F is not None else ca.SX.zeros(n)
        potential = evaluate(V, (q, t), (1, 1), "V(q, t)") if V is not None else ca.SX(0)
        momentum = ca.gradient(kinetic, v)
        self.A = ca.jacobian(momentum, v)
        h = ca.jacobian(momentum, q) @ v + ca.jacobian(momentum, t) - ca.gradient(kinetic, q)
        self.f = force - ca.gradient(potential, q) - h
        self.qdot = v
        self.energy = kinetic + potential
        self.F_nc = force

    def lagrange_rows(self, N: ca.SX) -> ca.SX:
        return _coordinate_lagrange_rows(N, self.q, self.v, self.t, self.qdot)


class MassMatrix(Mechanism):
    """Explicit equations ``A(q, t) q̈ = f(q, v, t)`` (multibody codes, published test sets).

    ``f`` already holds ``F − h`` including the velocity-squared terms, so nothing is added
    to it.

    Parameters
    ----------
    n : int
        Number of coordinates.
    A : callable ``(q, t) -> (n, n)``
        Mass matrix, symmetric positive definite.
    f : callable ``(q, v, t) -> (n,)``
        Right-hand side.
    energy : callable ``(q, v, t) -> scalar``, optional
        Total energy, recorded along trajectories when given.
    kinematics : callable ``(q, v, t) -> (nq,)``, optional
        ``q̇`` when ``v`` are quasi-velocities (then give ``nq``); default ``q̇ = v``.
    nq : int, optional
        Number of configuration coordinates when ``kinematics`` is given.
    nonconservative : callable ``(q, v, t) -> (n,)``, optional
        The non-conservative applied forces contained in ``f`` (zero if the system has none),
        so that trajectories can close the energy balance ``dE/dt = v·(F_nc + R)``; unknown
        (NaN work) if not given.
    """

    symmetric_by_construction = False

    def __init__(
        self,
        n: int,
        A: Expr,
        f: Expr,
        energy: Expr | None = None,
        kinematics: Expr | None = None,
        nq: int | None = None,
        nonconservative: Expr | None = None,
    ) -> None:
        n = _check_n(n)
        nq = n if nq is None else _check_n(nq)
        if kinematics is None and nq != n:
            raise InputError(f"MassMatrix: nq={nq} differs from n={n}; give the kinematics q̇ = K(q, v, t)")
        self._symbols(nq, n)
        q, v, t = self.q, self.v, self.t
        self.A = evaluate(A, (q, t), (n, n), "A(q, t)")
        self.f = evaluate(f, (q, v, t), (n, 1), "f(q, v, t)")
        self.qdot = v if kinematics is None else evaluate(kinematics, (q, v, t), (nq, 1), "kinematics(q, v, t)")
        self._coordinates = kinematics is None
        self.energy = evaluate(energy, (q, v, t), (1, 1), "energy(q, v, t)") if energy is not None else None
        if nonconservative is not None:
            self.F_nc = evaluate(nonconservative, (q, v, t), (n, 1), "nonconservative(q, v, t)")

    def lagrange_rows(self, N: ca.SX) -> ca.SX:
        if not self._coordinates:
            raise InputError(
                "MassMatrix with quasi-velocities: the Lagrange derivative [N] needs generalized coordinates "
                "(q̇ = v); use Lagrangian or RigidBody for inertial and mixed realizations"
            )
        return _coordinate_lagrange_rows(N, self.q, self.v, self.t, self.qdot)


def quaternion_to_matrix(p: ca.SX) -> ca.SX:
    """Rotation matrix (body → space) of a unit quaternion ``p = (w, x, y, z)``."""
    w, x, y, z = p[0], p[1], p[2], p[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        ca.horzcat(2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        ca.horzcat(2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    )


def normalize_quaternions(q: ca.SX, slices: list[slice]) -> ca.SX:
    """``q`` with each quaternion ``q[s]`` (``s`` in ``slices``) of unit length (symbols)."""
    if not slices:
        return q
    parts = [q[i] for i in range(q.numel())]
    for s in slices:
        unit = q[s] / ca.norm_2(q[s])
        for k, i in enumerate(range(s.start, s.stop)):
            parts[i] = unit[k]
    return ca.vertcat(*parts)


def normalize_quaternion_array(q: np.ndarray, slices: list[slice]) -> np.ndarray:
    """:func:`normalize_quaternions` on numbers (one configuration, or one per row)."""
    if not slices:
        return q
    out = np.array(q, float, copy=True)
    for s in slices:
        out[..., s] /= np.linalg.norm(out[..., s], axis=-1, keepdims=True)
    return out


class QuaternionCoordinates:
    """For a mechanism whose ``q`` holds unit quaternions at ``self._quaternions`` (slices): :meth:`normalize` and
    :meth:`normalize_array` bring each back to unit length."""

    _quaternions: list[slice]

    def normalize(self, q: ca.SX) -> ca.SX:
        """Each quaternion of ``q`` of unit length."""
        return normalize_quaternions(q, self._quaternions)

    def normalize_array(self, q: np.ndarray) -> np.ndarray:
        """:meth:`normalize` on numbers (one configuration, or one per row)."""
        return normalize_quaternion_array(q, self._quaternions)


def quaternion_rate(p: Any, w: Any) -> Any:
    """``ṗ = ½ p ⊗ (0, ω)``: a unit quaternion's rate for the angular velocity ``ω`` in the frame ``p`` carries."""
    pw, px, py, pz = p[0], p[1], p[2], p[3]
    return 0.5 * ca.vertcat(
        -px * w[0] - py * w[1] - pz * w[2],
        pw * w[0] + py * w[2] - pz * w[1],
        pw * w[1] + pz * w[0] - px * w[2],
        pw * w[2] + px * w[1] - py * w[0],
    )


class RigidBody(Mechanism):
    """A rigid body about a fixed point (or its centre of mass), in body angular velocity ``ω``.

    Configuration: a unit quaternion ``q = (w, x, y, z)`` (body → space); velocity: ``ω`` in body
    axes. ``T = ½ ωᵀ I ω`` and the Euler–Poincaré operator ``[f] = d/dt ∂f/∂ω + ω × ∂f/∂ω`` give
    Euler's equations ``I ω̇ + ω × I ω = M``, so ``A = I`` and ``f = M − ω × I ω``. The torque is
    counted as non-conservative: the energy recorded is ``½ ωᵀIω`` and the torque's power
    ``ω·M`` enters the work.
    Kinematics ``q̇ = ½ q ⊗ (0, ω)``.

    Parameters
    ----------
    inertia : (3, 3) array
        Inertia tensor in body axes, symmetric positive definite.
    torque : callable ``(R, w, t) -> (3,)``, optional
        Applied torque in body axes; ``R`` is the rotation matrix (body → space).
    """

    def __init__(self, inertia: Any, torque: Expr | None = None) -> None:
        I = check_constant_matrix("RigidBody", "inertia", inertia, (3, 3))
        if not np.allclose(I, I.T, rtol=1e-12, atol=0.0):
            raise InputError(f"inertia must be symmetric, got {I.tolist()}")
        if np.linalg.eigvalsh(I).min() <= 0:
            raise InputError(
                f"inertia must be positive definite, eigenvalues {np.linalg.eigvalsh(I).tolist()}; "
                "check its sign and units"
            )
        principal = np.linalg.eigvalsh(I)
        if principal[2] > (principal[0] + principal[1]) * (1 + 1e-9):  # a body's moments: I₃ ≤ I₁ + I₂
            raise InputError(
                f"inertia's principal moments {principal.tolist()} violate the triangle inequality (the largest "
                "exceeds the sum of the others): no body has them; check the matrix"
            )
        self.inertia = I
        self._symbols(4, 3)
        q, w, t = self.q, self.v, self.t
        self.rotation = quaternion_to_matrix(q)
        moment = (
            evaluate(torque, (self.rotation, w, t), (3, 1), "torque(R, w, t)") if torque is not None else ca.SX.zeros(3)
        )
        Iw = ca.SX(ca.DM(I)) @ w
        self.A = ca.SX(ca.DM(I))
        self.f = moment - ca.cross(w, Iw)
        self.qdot = quaternion_rate(q, w)
        self.energy = 0.5 * ca.dot(w, Iw)
        self.F_nc = moment

    def normalize(self, q: ca.SX) -> ca.SX:
        """Unit quaternion: ``q / |q|``."""
        return q / ca.norm_2(q)

    def normalize_array(self, q: np.ndarray) -> np.ndarray:
        """Unit quaternion: ``q / |q|`` (of each row for an ``(N, 4)`` array)."""
        return q / np.linalg.norm(q, axis=-1, keepdims=True)

    def variation_matrix(self) -> ca.SX:
        """``δω = η̇ + ω × η`` for an angular variation ``η`` in body axes."""
        w = self.v
        return ca.vertcat(
            ca.horzcat(0, -w[2], w[1]),
            ca.horzcat(w[2], 0, -w[0]),
            ca.horzcat(-w[1], w[0], 0),
        )

    def lagrange_rows(self, N: ca.SX) -> ca.SX:
        """Euler–Poincaré derivative ``[N_i] = d/dt ∂N_i/∂ω + ω × ∂N_i/∂ω``.

        Valid for ``N`` independent of the orientation (the case of the paper's §2 and §4).
        """
        if ca.depends_on(N, self.q):
            raise ShapeError(
                "RigidBody: N must not depend on the orientation q (the Euler–Poincaré form used "
                "here holds for N(ω, t) only); express N in body axes"
            )
        Nw = ca.jacobian(N, self.v)
        rows = []
        for i in range(N.numel()):
            p = Nw[i, :].T
            rows.append((ca.jacobian(p, self.t) + ca.cross(self.v, p)).T)
        return ca.vertcat(*rows) if rows else ca.SX(0, 3)
