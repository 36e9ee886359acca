"""A step's data as numbers at one instant: :class:`StepProblem`, the one type between the model's expressions
(:class:`~gausspp.step.equality.expressions.StepExpressions`) and the step's answer
(:class:`~gausspp.step.results.StepResult`).

Its first fields are ``A, f, r₀, J, φ, D, Φ`` of docs/theory.md §2: what :meth:`Model.step_data` returns, what
:func:`gausspp.step.equality.solve_numbers.solve` takes, and what the diagnosis of a failed step
(:mod:`gausspp.step.outcome`) reads; :meth:`StepProblem.create` builds them from numbers given by hand. Evaluated
at a model's state ``(t, q, v, λ)`` with Baumgarte terms ``stab = (α, β)`` (:func:`evaluate`, one compiled function
kept in the model's workspace) it also carries what the general step, the projection onto the constraints and the
impact law read: the holonomic residuals ``g``, the kinematics ``q̇``, the energy and the power of the
non-conservative forces, and the unilateral contacts' ``g_c, J_c, φ_c, ġ_c``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..errors import InputError, NonFiniteError, ShapeError
from ..workspace import workspace
from .equality.kernel import Bound, dense_outputs, load_inputs
from .protocol import StepModel

NO_STAB = np.zeros(2)


@dataclass(frozen=True)
class StepProblem:
    """``A q̈ = f + r₀ + D u``, ``J q̈ = φ`` at one instant.

    Attributes
    ----------
    A : (n, n) array     kinetic-energy (mass) matrix, symmetric positive definite
    f : (n,) array       ``F − h``
    r0 : (n,) array      known part of the reaction
    J : (k, n) array     ``∂Φ/∂v``
    phi : (k,) array     right-hand side of ``J q̈ = φ``
    D : (n, m) array     reaction directions
    Phi : (k,) array     constraint value at the state

    Evaluated at a model's state (empty, or 0, for a problem given by hand):

    g : (k,) array       holonomic residuals ``g(q, t)`` (0 on other rows)
    qdot : (nq,) array   ``q̇`` from the kinematics
    energy, power : float
        mechanical energy and power of the non-conservative forces; the energy is NaN where it is unknown (a
        mechanism without energy in :meth:`Model.step_data`, a problem given by hand), though :func:`evaluate`
        (internal: its values pass the steps' finiteness checks) gives 0 there
    gc, Jc, phic, gdotc : (nc,), (nc, n), (nc,), (nc,) arrays
        the unilateral contacts' gaps, Jacobian, right-hand side and gap rates
    """

    A: np.ndarray
    f: np.ndarray
    r0: np.ndarray
    J: np.ndarray
    phi: np.ndarray
    D: np.ndarray
    Phi: np.ndarray
    g: np.ndarray = field(default_factory=lambda: np.zeros(0))
    qdot: np.ndarray = field(default_factory=lambda: np.zeros(0))
    energy: float = float("nan")
    power: float = 0.0
    gc: np.ndarray = field(default_factory=lambda: np.zeros(0))
    Jc: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    phic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gdotc: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @classmethod
    def create(
        cls,
        A: object,
        f: object,
        J: object,
        phi: object,
        D: object | None = None,
        r0: object | None = None,
    ) -> StepProblem:
        """Check shapes and values; ``D`` defaults to ``Jᵀ`` (ideal), ``r0`` to zero."""
        A_ = _array("A", A, 2)
        n = A_.shape[0]
        if A_.shape != (n, n):
            raise ShapeError(f"A must be square, got shape {A_.shape}")
        J_ = _array("J", J, 2)
        k = J_.shape[0]
        if J_.shape[1] != n:
            raise ShapeError(f"J has shape {J_.shape}, expected ({k}, {n}) to match A")
        D_ = J_.T.copy() if D is None else _array("D", D, 2)
        if D_.shape[0] != n:
            raise ShapeError(f"D has shape {D_.shape}, expected ({n}, m)")
        f_ = _vector("f", f, n)
        r0_ = np.zeros(n) if r0 is None else _vector("r0", r0, n)
        return cls(A=A_, f=f_, r0=r0_, J=J_, phi=_vector("phi", phi, k), D=D_, Phi=np.zeros(k))

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(n, k, m)``: coordinates, constraint rows, reaction directions."""
        return self.A.shape[0], self.J.shape[0], self.D.shape[1]


def _array(name: str, value: object, ndim: int) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float, ndmin=ndim)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be numeric: {exc}") from None
    if arr.ndim != ndim:
        raise ShapeError(f"{name} must have {ndim} dimensions, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{name} contains NaN or inf")
    return arr


def _vector(name: str, value: object, size: int) -> np.ndarray:
    arr = _array(name, value, 1).ravel()
    if arr.shape != (size,):
        raise ShapeError(f"{name} has {arr.size} entries, expected {size}")
    return arr


#: The fields :func:`evaluate` fills, in the order of its compiled function's outputs.
_FIELDS = ("A", "f", "r0", "J", "phi", "D", "Phi", "g", "qdot", "energy", "power", "gc", "Jc", "phic", "gdotc")
_SCALARS = ("energy", "power")
_MATRICES = ("A", "J", "D", "Jc")


def _build(model: StepModel) -> Bound:
    p, mech, c = model.expressions, model.mechanism, model.contact_expressions
    outputs = [
        p.A,
        p.f,
        p.r0,
        p.J,
        p.phi,
        p.D,
        p.Phi,
        p.g if p.g is not None else ca.SX.zeros(model.k),
        mech.qdot,
        mech.energy if mech.energy is not None else ca.SX(0),
        ca.dot(mech.v, mech.F_nc) if mech.F_nc is not None else ca.SX(0),
        c.g,
        c.J,
        c.phi,
        c.gdot,
    ]
    fn = ca.Function("step_data", model.inputs, outputs)
    return Bound(ca.Function("step_data", model.inputs, dense_outputs(fn.call(model.inputs))))


def evaluate(
    model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: Any = NO_STAB
) -> StepProblem:
    """:class:`StepProblem` at ``(t, q, v, λ)``, every field (inputs already checked; no checks on the values)."""
    bound = workspace(model).get(("step-data",), lambda: _build(model))
    load_inputs(bound.args, (t, q, v, lam, stab))
    bound.eval()
    values: dict[str, Any] = {}
    for name, raw, shape in zip(_FIELDS, bound.res, bound.shapes, strict=True):
        if name in _SCALARS:
            values[name] = float(raw[0])
        elif name in _MATRICES:
            values[name] = raw.reshape(shape, order="F").copy()
        else:
            values[name] = raw.copy()
    return StepProblem(**values)
