"""A mechanism with its constraints and their realizations: the per-step problem, compiled.

``Model`` assembles DESIGN §2's step ``A q̈ = F − h + r₀ + D u``, ``J q̈ = φ`` from a front
end and constraints (stacking rows of ``J`` and columns of ``D``), compiles one kernel per
solver on first use, and keeps it: a step is then one casadi call. The model is immutable
after construction; kernels (with their bound buffers) are a per-model cache.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from . import qp
from ._outcome import Group, Where, evaluation_failed, to_result
from .constraints import Constraint
from .errors import InputError, MissingMultiplierError, NonFiniteError, ShapeError, UnknownNameError
from .frontends import Mechanism
from .kernel import Kernel, build_kernel
from .problem import StepProblem
from .results import StepResult
from .step import StepExpressions

SOLVERS = ("qp", "direct")
_NO_STAB = np.zeros(2)


class Model:
    """A mechanical system with constraints, each kept by its chosen realization.

    Parameters
    ----------
    mechanism : Lagrangian, RigidBody or MassMatrix
        The unconstrained system.
    constraints : Constraint or sequence of Constraint
        Each with its realization (ideal by default).
    margin_warn : float
        A step whose realizability margin is below this warns (:class:`RealizabilityWarning`).
    margin_error : float
        Below this the constraint is deemed unrealizable (:class:`RealizabilityError`).
    refine : bool
        One step of iterative refinement after each solve (default). It restores round-off
        accuracy where ``A`` is ill-conditioned and the constraints nearly fix the acceleration
        (``a = a₀ + A⁻¹Du`` cancels there); ``False`` shows each solver's raw answer.

    Attributes
    ----------
    nq, nv : int
        Sizes of ``q`` and ``v``.
    k : int
        Number of constraint rows; ``m`` the number of reaction unknowns.
    n_lam : int
        Size of the ``λ`` state (0 unless a realization carries ``λ``).
    row_names : list of str
        One name per constraint row.
    """

    def __init__(
        self,
        mechanism: Mechanism,
        constraints: Constraint | Sequence[Constraint],
        *,
        margin_warn: float = 1e-6,
        margin_error: float = 1e-12,
        refine: bool = True,
    ) -> None:
        if not isinstance(mechanism, Mechanism):
            raise InputError(f"mechanism must be a Lagrangian, RigidBody or MassMatrix, got {type(mechanism).__name__}")
        if isinstance(constraints, Constraint):
            constraints = [constraints]
        constraints = list(constraints)
        if not constraints:
            raise InputError("a Model needs at least one constraint")
        for c in constraints:
            if not isinstance(c, Constraint):
                raise InputError(f"constraints must be Constraint or Holonomic objects, got {type(c).__name__}")
        if not 0 <= margin_error < margin_warn:
            raise InputError(f"need 0 ≤ margin_error < margin_warn, got {margin_error} and {margin_warn}")
        self.mechanism = mechanism
        self.constraints = tuple(constraints)
        self.names = [c.name if c.name is not None else f"constraint {i}" for i, c in enumerate(constraints)]
        if len(set(self.names)) != len(self.names):
            raise InputError(f"constraint names must be unique, got {self.names}")
        self.margin_warn, self.margin_error, self.refine = margin_warn, margin_error, refine
        self._assemble()
        self._kernels: dict[tuple[str, str | None], Kernel] = {}
        self._data_fn: ca.Function | None = None
        self._projection: ca.Function | None = None

    def _assemble(self) -> None:
        mech = self.mechanism
        exprs = [c.expressions(mech) for c in self.constraints]
        sizes = [int(e.Phi.numel()) for e in exprs]
        self.n_lam = sum(k for k, c in zip(sizes, self.constraints, strict=True) if c.realization.has_state)
        self.lam = ca.SX.sym("lam", self.n_lam)
        Ds, r0, groups, lam0_parts, row_names, lam_cols = [], ca.SX.zeros(mech.nv), [], [], [], []
        row = col = lam_at = 0
        for c, e, k, name in zip(self.constraints, exprs, sizes, self.names, strict=True):
            real = c.realization
            lam_c = self.lam[lam_at : lam_at + k] if real.has_state else ca.SX(0, 1)
            if real.has_state:
                lam_at += k
                lam0_parts.append(self._lam0_of(real.lam0, k, name))
                lam_cols += list(range(col, col + k))  # u = λ̇ for these
            reaction = real.reaction(mech, e, lam_c)
            D = reaction.D
            if D.size1() != mech.nv:
                raise ShapeError(
                    f"constraint {name!r}: reaction directions D have shape {D.shape}, expected ({mech.nv}, m)"
                )
            Ds.append(D)
            r0 = r0 + reaction.r0
            groups.append(Group(name, slice(row, row + k), slice(col, col + D.size2()), real.hint, real.label))
            row_names += [name] if k == 1 else [f"{name}[{i}]" for i in range(k)]
            row, col = row + k, col + D.size2()
        self.k, self.m = row, col
        self.row_names = row_names
        self.lam_columns = lam_cols
        self._groups = groups
        known = [p for p in lam0_parts if p is not None]
        self._lam0: np.ndarray | None = None if len(known) < len(lam0_parts) else np.concatenate([np.zeros(0), *known])
        Phi = ca.vertcat(*[e.Phi for e in exprs])
        g = ca.vertcat(*[e.g if e.g is not None else ca.SX.zeros(k) for e, k in zip(exprs, sizes, strict=True)])
        self.holonomic_rows = [
            i
            for e, k, at in zip(exprs, sizes, np.cumsum([0, *sizes]), strict=False)
            if e.g is not None
            for i in range(at, at + k)
        ]
        # Baumgarte terms (DESIGN §5): J q̈ = φ − α Φ − β g, with (α, β) an input (zero: the exact step)
        self.stab = ca.SX.sym("stab", 2)
        self._expressions = StepExpressions(
            A=mech.A,
            f=mech.f,
            r0=r0,
            J=ca.vertcat(*[e.J for e in exprs]),
            phi=ca.vertcat(*[e.phi for e in exprs]) - self.stab[0] * Phi - self.stab[1] * g,
            D=ca.horzcat(*Ds),
            Phi=Phi,
            v=mech.v,
            qdot=mech.qdot,
            energy=mech.energy,
            F_nc=mech.F_nc,
            g=g,
        )
        self.has_energy = mech.energy is not None
        self.has_force_power = mech.F_nc is not None
        self._inputs = [mech.t, mech.q, mech.v, self.lam, self.stab]

    @staticmethod
    def _lam0_of(lam0: np.ndarray | None, k: int, name: str) -> np.ndarray | None:
        if lam0 is not None and lam0.shape != (k,):
            raise ShapeError(f"constraint {name!r}: lam0 has {lam0.size} entries, expected {k}")
        return lam0

    # -- sizes ------------------------------------------------------------------------------
    @property
    def nq(self) -> int:
        return self.mechanism.nq

    @property
    def nv(self) -> int:
        return self.mechanism.nv

    @property
    def lam0(self) -> np.ndarray | None:
        """Initial ``λ`` from the realizations (``None`` if one is missing; empty if no λ state)."""
        return None if self._lam0 is None else self._lam0.copy()

    # -- compiled kernels ------------------------------------------------------------------
    def kernel(self, solver: str = "qp", backend: str | qp.QPBackend | None = None) -> Kernel:
        """The compiled step for ``solver`` (and QP ``backend``), built on first use and kept.

        Its inputs are ``(t, q, v, lam, stab)`` (``stab`` = Baumgarte ``(α, β)``, zero for the exact
        step); write them into ``kernel.inputs`` and call ``kernel.evaluate()`` for the fastest
        possible step, or call ``kernel(t, q, v, lam, stab)``.
        """
        if solver not in SOLVERS:
            raise UnknownNameError(f"solver={solver!r} is unknown; use one of {list(SOLVERS)}")
        if solver == "direct" and backend is not None:
            raise InputError(f"backend={backend!r} applies to solver='qp' only")
        chosen = qp.get(backend) if solver == "qp" else None
        key = (solver, chosen.name if chosen else None)
        if key not in self._kernels or (
            chosen is not None and getattr(self._kernels[key], "backend", chosen) is not chosen
        ):
            self._kernels[key] = build_kernel("step", self._inputs, self._expressions, solver, chosen, self.refine)
        return self._kernels[key]

    # -- checked entry points ---------------------------------------------------------------
    def _state(self, t: Any, q: Any, v: Any, lam: Any) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise InputError(f"t must be a number, got {t!r}") from None
        if not np.isfinite(t):
            raise NonFiniteError(f"t is not finite: {t}")
        q = _state_vector("q", q, self.nq, t)
        v = _state_vector("v", v, self.nv, t)
        if self.n_lam == 0:
            if lam is not None and np.size(lam) != 0:
                raise InputError("lam was given but no realization of this model carries λ as a state")
            return t, q, v, np.zeros(0)
        if lam is None:
            if self._lam0 is None:
                missing = [
                    n
                    for n, c in zip(self.names, self.constraints, strict=True)
                    if c.realization.has_state and c.realization.lam0 is None
                ]
                raise MissingMultiplierError(
                    f"constraint(s) {missing} carry λ as a state and need its value: pass lam=... "
                    "or give lam0 to their realization"
                )
            lam = self._lam0
        return t, q, v, _state_vector("lam", lam, self.n_lam, t)

    def step(
        self,
        t: float,
        q: Any,
        v: Any,
        lam: Any = None,
        *,
        solver: str = "qp",
        backend: str | qp.QPBackend | None = None,
    ) -> StepResult:
        """Solve the step at ``(t, q, v, λ)``: Gauss's principle as a QP, or the direct formula.

        Parameters
        ----------
        t : float
        q : (nq,) array
        v : (nv,) array
        lam : (n_lam,) array, optional
            ``λ`` for realizations that carry it; defaults to their ``lam0``.
        solver : {"qp", "direct"}
        backend : str, optional
            QP backend name (see :func:`gausspp.qp.names`); default :data:`gausspp.qp.DEFAULT`.

        Raises
        ------
        RealizabilityError
            If the realization cannot keep a constraint at this state (margin below
            ``margin_error``).
        NotPositiveDefiniteError, NonFiniteError, ShapeError, QPSolveError
        """
        t, q, v, lam = self._state(t, q, v, lam)
        kernel = self.kernel(solver, backend)
        name = "direct" if solver == "direct" else qp.get(backend).name
        where = Where(t, name, self._groups, lambda: self.step_data(t, q, v, lam))
        try:
            out = kernel(t, q, v, lam, _NO_STAB)
        except RuntimeError as exc:  # casadi refused to evaluate (e.g. a QP plugin given NaN data)
            raise evaluation_failed(exc, where, margin_error=self.margin_error) from None
        return to_result(out, where, margin_warn=self.margin_warn, margin_error=self.margin_error)

    def step_data(self, t: float, q: Any, v: Any, lam: Any = None) -> StepProblem:
        """The step's ``A, f = F − h, r₀, J, φ, D, Φ`` as numbers (no checks on their values)."""
        t, q, v, lam = self._state(t, q, v, lam)
        if self._data_fn is None:
            p = self._expressions
            self._data_fn = ca.Function("step_data", self._inputs, [p.A, p.f, p.r0, p.J, p.phi, p.D, p.Phi])
        A, f, r0, J, phi, D, Phi = (np.array(x) for x in self._data_fn(t, q, v, lam, _NO_STAB))
        return StepProblem(A=A, f=f.ravel(), r0=r0.ravel(), J=J, phi=phi.ravel(), D=D, Phi=Phi.ravel())

    def __repr__(self) -> str:
        cons = ", ".join(f"{n} ({c.realization.label})" for n, c in zip(self.names, self.constraints, strict=True))
        return f"Model({type(self.mechanism).__name__}, nq={self.nq}, nv={self.nv}, constraints: {cons})"


def _state_vector(name: str, value: Any, size: int, t: float) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a numeric vector, got {value!r}") from None
    if arr.size != size:
        raise ShapeError(f"{name} has {arr.size} entries, expected {size} (at t={t:.6g})")
    if not np.isfinite(arr.sum()):
        raise NonFiniteError(f"{name} contains NaN or inf at t={t:.6g}: {arr.tolist()}")
    return arr
