"""Realizations: how a constraint is kept, and so which motion it produces (docs/theory.md §2).

Every realization gives the per-step reaction the same shape::

    A q̈ + h = F + r₀ + D u,      J q̈ = φ

with ``u`` the step's unknowns, ``D`` the reaction directions and ``r₀`` the part of the
reaction already known from the state (for realizations that carry ``λ`` as a state,
``u = λ̇``). Adding a realization means writing one small subclass of
:class:`Realization`.

=====================  ========  =====================================  ==================
realization            paper     reaction R                             virtual displ.
=====================  ========  =====================================  ==================
Ideal                  (2)–(4)   ``Jᵀ λ``                               ``J δx = 0``
Force(M) (Béghin)      (10)      ``Mᵀ λ``                               ``M δx = 0``
Inertial(N)            (14)      ``−λ̇ N_v − λ [N]``                     (20) with M = 0
Vakonomic              (17)      inertial with ``N = Φ``                ``δΦ = 0``
Mixed, proportional    (19)      ``−λ̇ N_v − λ [N] + λ M``               ``δN + M δx = 0``
Mixed, rate            (22)      ``−λ̇ N_v − λ [N] + λ̇ M``               ``δN − (M δx)˙ = 0``
=====================  ========  =====================================  ==================
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from ..errors import InputError, NonFiniteError, ShapeError, UnknownNameError
from ..validation import array
from .constraint_expressions import ConstraintExpressions
from .symbolic import evaluate, require_affine_in

if TYPE_CHECKING:
    from .mechanism import Mechanism


@dataclass(frozen=True)
class Reaction:
    """The reaction's per-step form ``R = r₀ + D u``.

    Attributes
    ----------
    D : (nv, m) SX
        Reaction directions (columns).
    r0 : (nv,) SX
        Known part (from ``λ`` in the state).
    """

    D: ca.SX
    r0: ca.SX


@dataclass(frozen=True)
class VirtualDisplacements:
    """The realization's virtual displacements along a path, eq. (20): ``E1 η̇ + E0 η = 0``.

    ``η`` is a variation in velocity space (``δq = K η``, ``δv = η̇ + C η``, see
    :meth:`Mechanism.variation_matrix`). ``E1`` is ``None`` when the relation holds pointwise
    (``N = 0``: ``E0 η = 0`` at each instant).
    """

    E1: ca.SX | None
    E0: ca.SX


class Realization(ABC):
    """How a constraint is kept. Subclasses fulfil this contract:

    1. ``has_state`` — ``True`` if ``λ`` is carried as a state and ``u = λ̇``
       (then ``lam0`` holds its initial value, or ``None`` if the user gives it later);
    2. :meth:`reaction` — given the mechanism, the constraint's expressions and the
       symbol ``lam`` (size ``k`` when ``has_state``, else size 0), return ``D`` and ``r₀``;
    3. :meth:`virtual_displacements` — the relation (20) that defines its virtual
       displacements along a path with acceleration ``a`` (used by :func:`gausspp.verify`);
    4. ``label`` — a short name for tables.
    """

    has_state: bool = False
    label: str = "realization"
    lam0: np.ndarray | None = None
    #: Bounds ``(lo, hi)`` on the reaction unknowns ``u``, as given (``None``: unbounded; see :class:`Force`).
    bounds: tuple[np.ndarray, np.ndarray] | None = None
    #: What to change when the realization cannot keep the constraint (used in messages).
    hint: str = "choose reaction directions D with J A⁻¹ D nonsingular"

    @abstractmethod
    def reaction(self, mech: Mechanism, c: ConstraintExpressions, lam: ca.SX) -> Reaction:
        """The reaction's directions ``D`` and known part ``r₀`` for one constraint."""

    def bounds_for(self, m: int) -> tuple[np.ndarray, np.ndarray] | None:
        """:attr:`bounds` for ``m`` reaction unknowns (one pair of arrays of length ``m``), or ``None``."""
        return None if self.bounds is None else _bounds(self.bounds, m)

    @abstractmethod
    def virtual_displacements(self, mech: Mechanism, c: ConstraintExpressions, a: ca.SX) -> VirtualDisplacements:
        """Eq. (20) for this realization: ``E1 η̇ + E0 η = 0`` (``a`` is the path's acceleration)."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def _variation_of(N: ca.SX, mech: Mechanism) -> tuple[ca.SX, ca.SX]:
    """``δN = N_v η̇ + (N_v C + N_q K) η`` for ``N`` affine in ``v``: returns ``(N_v, N_v C + N_q K)``."""
    Nv = ca.jacobian(N, mech.v)
    K = ca.jacobian(mech.qdot, mech.v)
    return Nv, Nv @ mech.variation_matrix() + ca.jacobian(N, mech.q) @ K


class Ideal(Realization):
    """Ideal constraint (d'Alembert–Lagrange, eqs. (2)–(4)): ``R = Jᵀλ``, ``δx`` with ``J δx = 0``."""

    label = "ideal"
    hint = "the constraint rows are dependent (redundant constraints): remove the redundant rows"

    def reaction(self, mech: Mechanism, c: ConstraintExpressions, lam: ca.SX) -> Reaction:
        return Reaction(D=c.J.T, r0=ca.SX.zeros(mech.nv))

    def virtual_displacements(self, mech: Mechanism, c: ConstraintExpressions, a: ca.SX) -> VirtualDisplacements:
        return VirtualDisplacements(E1=None, E0=c.J)


def _matrix(fn: Callable[..., Any], mech: Mechanism, k: int, what: str) -> ca.SX:
    return evaluate(fn, (mech.q, mech.v, mech.t), (k, mech.nv), what)


def _initial(lam0: Any) -> np.ndarray | None:
    if lam0 is None:
        return None
    arr = np.atleast_1d(array("realization", "lam0", lam0, finite=False))
    if arr.ndim != 1:
        raise ShapeError(f"lam0 must be a vector, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"lam0 contains NaN or inf: {arr.tolist()}")
    return arr


class Force(Realization):
    """Béghin servo-constraint (eqs. (10), (13)): a controlled force ``R = Mᵀλ``.

    The constraint is kept by actuators pushing along the rows of ``M``; the virtual
    displacements are ``M δx = 0``. With one actuator per constraint row (``M`` is ``k × nv``)
    it is realizable iff ``J A⁻¹ Mᵀ`` is nonsingular (12), and the force is unique.

    **Over-actuation.** ``M`` may have more rows (actuators) than the constraint has (``m > k``):
    then many forces keep the constraint and Gauss's principle picks the one of least compulsion,
    ``min uᵀ(M A⁻¹ Mᵀ)u`` subject to ``J A⁻¹ Mᵀ u = φ − J a₀`` — solved by the QP
    (``solver="qp"``; the direct formula needs a square ``S``).

    **Bounds.** ``bounds=(lo, hi)`` limits each actuator's ``λ`` (scalars or length-``m``
    arrays, ``±inf`` for a free side). While the needed force is within the bounds, the motion
    is that of the unbounded servo. When it is not, the actuators *saturate* and the constraint
    can only be tracked: the step first minimizes the tracking error
    ``Σᵢ (Jᵢ a − φᵢ)² / (Jᵢ A⁻¹ Jᵢᵀ)`` (the compulsion an ideal constraint would need to correct
    the acceleration), then the compulsion among the minimizers (see :mod:`gausspp.step.general`).
    Physically: the actuator pushes as hard as it may in the direction that keeps the constraint
    best, and the error is reported (``StepResult.tracking_error``). A saturated servo leaves
    the constraint; add Baumgarte feedback (``stabilize="baumgarte"``) so that it returns to it
    after the saturation ends.

    Parameters
    ----------
    M : callable ``(q, v, t) -> (m, nv)``
        Force directions, one row per actuator (``m ≥ k``).
    bounds : (lo, hi), optional
        Bounds on each actuator's multiplier ``λ``.
    """

    label = "force"
    hint = "choose force directions M with J A⁻¹ Mᵀ nonsingular, i.e. M not A-orthogonal to ∂Φ/∂v (condition (12))"

    def __init__(self, M: Callable[..., Any], bounds: Any = None) -> None:
        self.M = M
        if bounds is not None:
            if not isinstance(bounds, (tuple, list)) or len(bounds) != 2:
                raise InputError(f"Force: bounds must be a pair (lo, hi), got {bounds!r}")
            lo, hi = (np.atleast_1d(array("Force", "bounds", b, finite=False)) for b in bounds)
            if np.any(np.isnan(lo)) or np.any(np.isnan(hi)):
                raise NonFiniteError(f"Force: bounds contain NaN: {bounds!r}")
            if lo.ndim != 1 or hi.ndim != 1:
                raise ShapeError(f"Force: bounds must be scalars or vectors, got shapes {lo.shape}, {hi.shape}")
            crossed = np.broadcast_to(lo, np.broadcast_shapes(lo.shape, hi.shape)) > hi
            if np.any(crossed):
                raise InputError(f"Force: a lower bound exceeds its upper bound: bounds={bounds!r} (need lo ≤ hi)")
            self.bounds = (lo, hi)
            self.label = "force (bounded)"

    def _M(self, mech: Mechanism, c: ConstraintExpressions) -> ca.SX:
        M = evaluate(self.M, (mech.q, mech.v, mech.t), (None, mech.nv), "Force: M(q, v, t)")
        k = c.J.shape[0]
        if M.size1() < k:
            raise ShapeError(
                f"Force: M has {M.size1()} rows (actuators) for a constraint with {k} rows: fewer actuators than "
                "constraint rows can never keep it; give at least one actuator per row"
            )
        return M

    def reaction(self, mech: Mechanism, c: ConstraintExpressions, lam: ca.SX) -> Reaction:
        return Reaction(D=self._M(mech, c).T, r0=ca.SX.zeros(mech.nv))

    def virtual_displacements(self, mech: Mechanism, c: ConstraintExpressions, a: ca.SX) -> VirtualDisplacements:
        M = self._M(mech, c)
        if M.size1() == c.J.shape[0]:
            return VirtualDisplacements(E1=None, E0=M)
        # over-actuated: the least-compulsion reaction is R = Mᵀ H⁻¹ Sᵀ y (H = M A⁻¹ Mᵀ, S = J A⁻¹ Mᵀ), so
        # the motion is characterized by the k relations S H⁻¹ M δx = 0 (for m = k they are M δx = 0)
        AinvMt = ca.solve(mech.A, M.T)
        S = c.J @ AinvMt
        return VirtualDisplacements(E1=None, E0=S @ ca.solve(M @ AinvMt, M))

    def __repr__(self) -> str:
        return "Force()" if self.bounds is None else f"Force(bounds=({self.bounds[0]}, {self.bounds[1]}))"


def _bounds(bounds: Any, m: int) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = (
        np.broadcast_to(np.asarray(b, dtype=float), (m,)).copy() if np.size(b) in (1, m) else None for b in bounds
    )
    if lo is None or hi is None:
        raise ShapeError(f"Force: bounds need 1 or {m} entries (one per actuator), got {bounds!r}")
    if np.any(lo > hi):
        raise InputError(f"Force: a lower bound exceeds its upper bound: lo={lo.tolist()}, hi={hi.tolist()}")
    return lo, hi


class Inertial(Realization):
    """Inertial (flywheel) realization (eqs. (14)–(15)): ``T* = T + λ N``.

    The constraint is kept by changing the inertia: ``λ`` (e.g. a rotor's relative angular
    momentum) is a state with ``λ(t₀) = lam0``; the reaction is ``R = −λ̇ N_v − λ [N]``.
    Realizable iff ``J A⁻¹ N_vᵀ`` is nonsingular (16).

    Parameters
    ----------
    N : callable ``(q, v, t) -> (k,)``
        Affine in the velocities.
    lam0 : (k,) array, optional
        Initial ``λ``; may also be given to ``step``/``simulate``.
    """

    has_state = True
    label = "inertial"
    hint = "choose N with J A⁻¹ N_vᵀ nonsingular (condition (16)), e.g. a rotor axis not A-orthogonal to ∂Φ/∂v"

    def __init__(self, N: Callable[..., Any], lam0: Any = None) -> None:
        self.N = N
        self.lam0 = _initial(lam0)

    def _N(self, mech: Mechanism, c: ConstraintExpressions) -> ca.SX:
        N = evaluate(self.N, (mech.q, mech.v, mech.t), (c.J.shape[0], 1), f"{type(self).__name__}: N(q, v, t)")
        require_affine_in(N, mech.v, f"{type(self).__name__}: N(q, v, t)")
        return N

    def reaction(self, mech: Mechanism, c: ConstraintExpressions, lam: ca.SX) -> Reaction:
        N = self._N(mech, c)
        return Reaction(D=-ca.jacobian(N, mech.v).T, r0=-mech.lagrange_rows(N).T @ lam)

    def virtual_displacements(self, mech: Mechanism, c: ConstraintExpressions, a: ca.SX) -> VirtualDisplacements:
        E1, E0 = _variation_of(self._N(mech, c), mech)  # δN = 0
        return VirtualDisplacements(E1=E1, E0=E0)


class Vakonomic(Inertial):
    """Vakonomic realization (eqs. (17)–(18)): the inertial one with ``N = Φ``.

    Parameters
    ----------
    lam0 : (k,) array, optional
        Initial multiplier.
    """

    label = "vakonomic"

    def __init__(self, lam0: Any = None) -> None:
        self.lam0 = _initial(lam0)

    def _N(self, mech: Mechanism, c: ConstraintExpressions) -> ca.SX:
        return c.Phi  # affine in the velocities: every constraint is (checked by Constraint.expressions)


class Mixed(Realization):
    """Mixed realization: inertia and a controlled force together (eqs. (19)–(22)).

    ``law="proportional"`` (19), force multiplier ``λ′ = λ``:
    ``R = −λ̇ N_v − λ[N] + Mᵀλ``, virtual displacements ``δN + M δx = 0`` (20).
    ``law="rate"`` (22), ``λ′ = λ̇``: ``R = −λ̇ N_v − λ[N] + Mᵀλ̇``, virtual displacements
    ``δN − (M δx)˙ = 0``.

    Parameters
    ----------
    N : callable ``(q, v, t) -> (k,)``
        Affine in the velocities.
    M : callable ``(q, v, t) -> (k, nv)``
        Force directions.
    law : {"proportional", "rate"}
    lam0 : (k,) array, optional
    """

    has_state = True
    laws = ("proportional", "rate")
    hint = "choose N (and for law='rate' also M) so that J A⁻¹ D is nonsingular (condition (16))"

    def __init__(
        self, N: Callable[..., Any], M: Callable[..., Any], law: str = "proportional", lam0: Any = None
    ) -> None:
        if law not in self.laws:
            raise UnknownNameError(f"Mixed: law={law!r} is unknown; use one of {list(self.laws)}")
        self.N, self.M, self.law = N, M, law
        self.lam0 = _initial(lam0)
        self.label = f"mixed-{law}"

    def reaction(self, mech: Mechanism, c: ConstraintExpressions, lam: ca.SX) -> Reaction:
        k = c.J.shape[0]
        N = evaluate(self.N, (mech.q, mech.v, mech.t), (k, 1), "Mixed: N(q, v, t)")
        require_affine_in(N, mech.v, "Mixed: N(q, v, t)")
        M = _matrix(self.M, mech, k, "Mixed: M(q, v, t)")
        inertial = -mech.lagrange_rows(N).T @ lam
        D = -ca.jacobian(N, mech.v).T
        if self.law == "proportional":
            return Reaction(D=D, r0=inertial + M.T @ lam)
        return Reaction(D=D + M.T, r0=inertial)

    def virtual_displacements(self, mech: Mechanism, c: ConstraintExpressions, a: ca.SX) -> VirtualDisplacements:
        k = c.J.shape[0]
        N = evaluate(self.N, (mech.q, mech.v, mech.t), (k, 1), "Mixed: N(q, v, t)")
        M = _matrix(self.M, mech, k, "Mixed: M(q, v, t)")
        E1, E0 = _variation_of(N, mech)
        if self.law == "proportional":  # (20): δN + M η = 0
            return VirtualDisplacements(E1=E1, E0=E0 + M)
        # (22): δN − (M η)˙ = 0, with Ṁ along the path
        rows = [
            ca.jacobian(M[i, :].T, mech.q) @ mech.qdot
            + ca.jacobian(M[i, :].T, mech.v) @ a
            + ca.jacobian(M[i, :].T, mech.t)
            for i in range(k)
        ]
        M_dot = ca.horzcat(*rows).T
        return VirtualDisplacements(E1=E1 - M, E0=E0 - M_dot)

    def __repr__(self) -> str:
        return f"Mixed(law={self.law!r})"


#: Realizations given by name (``Holonomic(..., realization="vakonomic")``): name → a function making one. One entry
#: here registers a parameter-free realization of one's own (a subclass of :class:`Realization`);
#: ``tests/test_extension_points.py`` registers a toy one and simulates and verifies with it.
REALIZATIONS: dict[str, Callable[[], Realization]] = {"ideal": Ideal, "vakonomic": Vakonomic}


def as_realization(value: Realization | str | None) -> Realization:
    """Accept an instance, ``None`` (ideal) or a name of a parameter-free realization."""
    if value is None:
        return Ideal()
    if isinstance(value, Realization):
        return value
    if isinstance(value, str):
        if value in REALIZATIONS:
            made = REALIZATIONS[value]()
            if not isinstance(made, Realization):
                raise InputError(f"realization {value!r} is registered to make {made!r}, not a Realization")
            return made
        raise UnknownNameError(
            f"realization={value!r} is unknown; by name only {sorted(REALIZATIONS)} can be given, "
            "the others need their data: Force(M=...), Inertial(N=..., lam0=...), Mixed(N=..., M=..., law=...)"
        )
    raise InputError(f"realization must be a Realization or a name, got {type(value).__name__}")
