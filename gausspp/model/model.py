"""A mechanism with its constraints and their realizations: the per-step problem, compiled.

``Model`` assembles docs/theory.md §2's step ``A q̈ = F − h + r₀ + D u``, ``J q̈ = φ`` from a front
end and constraints (stacking rows of ``J`` and columns of ``D``), compiles one kernel per
solver on first use, and keeps it: a step is then one casadi call. The model is immutable
after construction; kernels (with their bound buffers) are a per-model cache.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from ..errors import (
    GaussppError,
    InputError,
    MissingMultiplierError,
    NonFiniteError,
    QPSolveError,
    RealizabilityError,
    ShapeError,
    UnknownNameError,
)
from ..step import qp
from ..step.expressions import StepExpressions
from ..step.general import CONSISTENCY_TOL, GaussProblem, GaussSolution, check_backend, solve_general
from ..step.kernel import Kernel, _Bound, _dense, _load, build_kernel
from ..step.outcome import Group, Where, evaluation_failed, to_result, warn_small_margin
from ..step.problem import StepProblem
from ..step.realizability import cosines
from ..step.redundancy import CLEARLY_INDEPENDENT, independent_rows
from ..step.results import ImpactResult, StepResult
from ..validation import positive
from .constraints import Constraint, Unilateral
from .mechanism import Mechanism

SOLVERS = ("qp", "direct")
#: Nearest state on the manifold: a row residual (as a coordinate distance) above this fraction of the state's
#: size means that the dependent rows cannot hold together — they contradict each other.
REACH_TOL = 1e-8
_DIRECT_NEEDS_INDEPENDENT_ROWS = (
    " (solver='direct' needs independent rows; solver='qp' returns the unique acceleration "
    "and the least-norm multiplier when the rows are redundant)"
)
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
        contact_tol: float = 1e-9,
        _allow_free: bool = False,
    ) -> None:
        if not isinstance(mechanism, Mechanism):
            raise InputError(f"mechanism must be a Lagrangian, RigidBody or MassMatrix, got {type(mechanism).__name__}")
        if isinstance(constraints, Constraint):
            constraints = [constraints]
        constraints = list(constraints)
        if not constraints and not _allow_free:
            raise InputError("a Model needs at least one constraint")
        for c in constraints:
            if not isinstance(c, Constraint):
                raise InputError(
                    f"constraints must be Constraint, Holonomic or Unilateral objects, got {type(c).__name__}"
                )
        margin_warn = positive("margin_warn", margin_warn)
        margin_error = positive("margin_error", margin_error, zero_ok=True)
        contact_tol = positive("contact_tol", contact_tol, zero_ok=True)
        if not margin_error < margin_warn:
            raise InputError(f"need 0 ≤ margin_error < margin_warn, got {margin_error} and {margin_warn}")
        self.mechanism = mechanism
        all_names = [c.name if c.name is not None else f"constraint {i}" for i, c in enumerate(constraints)]
        if len(set(all_names)) != len(all_names):
            raise InputError(f"constraint names must be unique, got {all_names}")
        bilateral = [(c, n) for c, n in zip(constraints, all_names, strict=True) if not isinstance(c, Unilateral)]
        unilateral = [(c, n) for c, n in zip(constraints, all_names, strict=True) if isinstance(c, Unilateral)]
        self.constraints = tuple(c for c, _ in bilateral)
        self.names = [n for _, n in bilateral]
        #: The unilateral contacts ``g(q, t) ≥ 0`` (kept apart from the bilateral constraints).
        self.contacts: tuple[Unilateral, ...] = tuple(c for c, _ in unilateral)
        self.contact_names = [n for _, n in unilateral]
        self.margin_warn, self.margin_error, self.refine = margin_warn, margin_error, refine
        self.contact_tol = float(contact_tol)
        self._assemble()
        self._assemble_contacts()
        #: True if some realization has bounds on its reaction (bounded servo, :class:`~gausspp.Force`).
        self.bounded = any(b is not None for b in self.group_bounds)
        self._general_fn: _Bound | None = None
        self._kernels: dict[tuple[str, str | None, bool], Kernel] = {}
        self._data_fn: ca.Function | None = None
        self._projection: ca.Function | None = None
        self._kinematics_fn: ca.Function | None = None

    def _assemble(self) -> None:
        mech = self.mechanism
        exprs = [c.expressions(mech) for c in self.constraints]
        sizes = [int(e.Phi.numel()) for e in exprs]
        self.n_lam = sum(k for k, c in zip(sizes, self.constraints, strict=True) if c.realization.has_state)
        self.lam = ca.SX.sym("lam", self.n_lam)
        Ds, r0, groups, lam0_parts, row_names, lam_cols = [], ca.SX.zeros(mech.nv), [], [], [], []
        group_bounds: list[tuple[np.ndarray, np.ndarray] | None] = []
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
            group_bounds.append(real.bounds_for(D.size2()))
            r0 = r0 + reaction.r0
            groups.append(Group(name, slice(row, row + k), slice(col, col + D.size2()), real.hint, real.label))
            row_names += [name] if k == 1 else [f"{name}[{i}]" for i in range(k)]
            row, col = row + k, col + D.size2()
        self.k, self.m = row, col
        self.row_names = row_names
        self.lam_columns = lam_cols
        self.groups = groups
        self.group_bounds = group_bounds  # per constraint: bounds on its reaction unknowns, or None
        known = [p for p in lam0_parts if p is not None]
        self._lam0: np.ndarray | None = None if len(known) < len(lam0_parts) else np.concatenate([np.zeros(0), *known])
        Phi = ca.vertcat(ca.SX(0, 1), *[e.Phi for e in exprs])
        g = ca.vertcat(
            ca.SX(0, 1), *[e.g if e.g is not None else ca.SX.zeros(k) for e, k in zip(exprs, sizes, strict=True)]
        )
        self.holonomic_rows = [
            i
            for e, k, at in zip(exprs, sizes, np.cumsum([0, *sizes]), strict=False)
            if e.g is not None
            for i in range(at, at + k)
        ]
        # Baumgarte terms (docs/theory.md §5): J q̈ = φ − α Φ − β g, with (α, β) an input (zero: the exact step)
        self.stab = ca.SX.sym("stab", 2)
        self.expressions = StepExpressions(
            A=mech.A,
            f=mech.f,
            r0=r0,
            J=ca.vertcat(ca.SX(0, mech.nv), *[e.J for e in exprs]),
            phi=ca.vertcat(ca.SX(0, 1), *[e.phi for e in exprs]) - self.stab[0] * Phi - self.stab[1] * g,
            D=ca.horzcat(ca.SX(mech.nv, 0), *Ds),
            Phi=Phi,
            v=mech.v,
            qdot=mech.qdot,
            energy=mech.energy,
            F_nc=mech.F_nc,
            g=g,
        )
        self.has_energy = mech.energy is not None
        self.has_force_power = mech.F_nc is not None
        self.inputs = [mech.t, mech.q, mech.v, self.lam, self.stab]

    def _assemble_contacts(self) -> None:
        mech = self.mechanism
        exprs = [c.expressions(mech) for c in self.contacts]
        self.contact_rows = [int(e.Phi.numel()) for e in exprs]
        self.contact_row_names = [
            name if k == 1 else f"{name}[{i}]"
            for name, k in zip(self.contact_names, self.contact_rows, strict=True)
            for i in range(k)
        ]
        self.contact_expressions = (
            ca.vertcat(ca.SX(0, 1), *[e.g for e in exprs if e.g is not None]),
            ca.vertcat(ca.SX(0, mech.nv), *[e.J for e in exprs]),
            ca.vertcat(ca.SX(0, 1), *[e.phi for e in exprs]),
            ca.vertcat(ca.SX(0, 1), *[e.Phi for e in exprs]),
        )
        self.restitution = (
            np.repeat([c.restitution for c in self.contacts], self.contact_rows) if self.contacts else np.zeros(0)
        )

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
    def kernel(
        self, solver: str = "qp", backend: str | qp.QPBackend | None = None, refine: bool | None = None
    ) -> Kernel:
        """The compiled step for ``solver`` (and QP ``backend``), built on first use and kept.

        Its inputs are ``(t, q, v, lam, stab)`` (``stab`` = Baumgarte ``(α, β)``, zero for the exact
        step); write them into ``kernel.inputs`` and call ``kernel.evaluate()`` for the fastest
        possible step, or call ``kernel(t, q, v, lam, stab)``. ``refine`` overrides the model's
        ``refine`` (``False``: each solver's raw answer).
        """
        refine = self.refine if refine is None else bool(refine)
        if solver not in SOLVERS:
            raise UnknownNameError(f"solver={solver!r} is unknown; use one of {list(SOLVERS)}")
        if self.contacts or self.bounded:
            raise InputError(
                "this model has unilateral contacts or bounded actuators: its step is the general Gauss QP, "
                "solved from Python (model.step(..., solver='qp')), not a compiled kernel"
            )
        if solver == "direct" and backend is not None:
            raise InputError(f"backend={backend!r} applies to solver='qp' only")
        chosen = qp.get(backend) if solver == "qp" else None
        key = (solver, chosen.name if chosen else None, refine)
        if key not in self._kernels or (
            chosen is not None and getattr(self._kernels[key], "backend", chosen) is not chosen
        ):
            self._kernels[key] = build_kernel("step", self.inputs, self.expressions, solver, chosen, refine)
        return self._kernels[key]

    # -- checked entry points ---------------------------------------------------------------
    def checked_state(self, t: Any, q: Any, v: Any, lam: Any) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
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
        refine: bool | None = None,
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
        refine : bool, optional
            One step of iterative refinement after the solve (default: the model's ``refine``);
            ``False`` returns the solver's raw answer (see :func:`gausspp.crosscheck`).

        Raises
        ------
        RealizabilityError
            If the realization cannot keep a constraint at this state (margin below
            ``margin_error``).
        NotPositiveDefiniteError, NonFiniteError, ShapeError, QPSolveError
        """
        t, q, v, lam = self.checked_state(t, q, v, lam)
        if self.contacts or self.bounded:
            if solver != "qp":
                raise InputError(
                    f"solver={solver!r}: a model with unilateral contacts or bounded actuators has no closed-form "
                    "step (inequalities); use solver='qp'"
                )
            return self.general_step(t, q, v, lam, backend=_backend_name(backend))[0]
        kernel = self.kernel(solver, backend, refine)
        name = "direct" if solver == "direct" else qp.get(backend).name
        where = Where(t, name, self.groups, lambda: self.step_data(t, q, v, lam))
        try:
            out = kernel(t, q, v, lam, _NO_STAB)
        except RuntimeError as exc:  # casadi refused to evaluate (e.g. a QP plugin given NaN data)
            raise evaluation_failed(exc, where, margin_error=self.margin_error) from None
        except QPSolveError as exc:  # a nearly singular step the backend could not solve: redundant rows?
            if solver == "direct" or self.k < 2:
                raise
            return self._redundant_step(t, q, v, lam, exc, backend)
        try:
            result = to_result(out, where, margin_warn=0.0, margin_error=self.margin_error)
        except (RealizabilityError, QPSolveError) as exc:
            if isinstance(exc, QPSolveError) and (solver == "direct" or self.k < 2):
                raise
            if solver == "direct":
                exc.args = (f"{exc}{_DIRECT_NEEDS_INDEPENDENT_ROWS}",)
                raise
            return self._redundant_step(t, q, v, lam, exc, backend)
        if result.margin >= self.margin_warn:
            return result
        # A small margin: nearly dependent rows. If they are dependent on the constraint manifold (and
        # independent here only by round-off or drift), solving them exactly would amplify the drift by
        # 1/margin — the general QP keeps the independent rows instead (gausspp.redundancy).
        if self.k > 1:
            try:
                general, solution = self.general_step(t, q, v, lam, backend=_backend_name(backend))
            except GaussppError:
                general, solution = None, None
            if general is not None and solution is not None and solution.redundant_rows > 0:
                if solver == "direct":
                    raise RealizabilityError(
                        f"the constraint rows of {', '.join(map(repr, self.names))} are redundant on the constraint "
                        f"manifold at t={t:.6g} (margin here "
                        f"{result.margin:.3g}, by the state's distance from the manifold)"
                        + _DIRECT_NEEDS_INDEPENDENT_ROWS,
                        t=t,
                        constraint=", ".join(self.names),
                        margin=result.margin,
                    )
                return general
        warn_small_margin(result.margin, t, self.groups, self.margin_warn)
        return result

    def _redundant_step(
        self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, exc: Exception, backend: Any
    ) -> StepResult:
        """The compiled QP refused a singular step: if the rows are merely redundant, the general QP answers."""
        try:
            result, solution = self.general_step(t, q, v, lam, backend=_backend_name(backend))
        except (RealizabilityError, QPSolveError) as general:  # the compiled step's message names the cause
            exc.args = (f"{exc} [the general QP: {general}]",)
            raise exc from None
        if solution.redundant_rows == 0:
            raise exc
        return result

    # -- the general Gauss QP (inequalities, bounds, redundancy) -----------------------------
    def evaluate_data(self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: Any) -> list[np.ndarray]:
        if self._general_fn is None:
            p, mech = self.expressions, self.mechanism
            gc, Jc, phic, gdotc = self.contact_expressions
            power = ca.dot(mech.v, mech.F_nc) if mech.F_nc is not None else ca.SX(0)
            energy = mech.energy if mech.energy is not None else ca.SX(0)
            fn = ca.Function(
                "general_data",
                self.inputs,
                [
                    p.A,
                    p.f,
                    p.r0,
                    p.J,
                    p.phi,
                    p.D,
                    p.Phi,
                    p.g if p.g is not None else ca.SX.zeros(self.k),
                    mech.qdot,
                    energy,
                    power,
                    gc,
                    Jc,
                    phic,
                    gdotc,
                ],
            )
            self._general_fn = _Bound(ca.Function("general_data", self.inputs, _dense(fn.call(self.inputs))))
        bound = self._general_fn
        _load(bound.args, (t, q, v, lam, stab))
        bound.eval()
        return [r.reshape(bound.fn.size_out(i), order="F").copy() for i, r in enumerate(bound.res)]

    def general_step(
        self,
        t: float,
        q: Any,
        v: Any,
        lam: Any = None,
        *,
        backend: str | None = None,
        stab: Any = _NO_STAB,
        closed: Any = None,
    ) -> tuple[StepResult, GaussSolution]:
        """The step by the general Gauss QP (:mod:`gausspp.step.general`): contacts, bounds, redundancy.

        A contact is *closed* when its gap is within ``contact_tol`` of zero (or when it is listed
        in ``closed``, indices of contact rows, as an event-driven simulation knows); closed contacts enter
        as ``g̈ ≥ 0`` with a force ``λ ≥ 0``. A closed contact that is still approaching
        (``ġ < −contact_tol``) needs an impact first (:meth:`impact`): that is an error here.
        ``backend`` is a qpsolvers solver (default: daqp if installed, else OSQP).

        Returns the :class:`StepResult` and the QP's own :class:`~gausspp.step.general.GaussSolution`.
        """
        t, q, v, lam = self.checked_state(t, q, v, lam)
        result, sol, _ = self.general_step_full(t, q, v, lam, backend, stab, closed)
        return result, sol

    def general_step_full(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        lam: np.ndarray,
        backend: str | None,
        stab: Any,
        closed: Any = None,
        consistency_tol: float = CONSISTENCY_TOL,
    ) -> tuple[StepResult, GaussSolution, dict[str, np.ndarray]]:
        """:meth:`general_step` on checked inputs; also returns kinematics, energy, powers and ``g``."""
        A, f, r0, J, phi, D, Phi, g, qdot, energy, power, gc, Jc, phic, gdotc = self.evaluate_data(t, q, v, lam, stab)
        f, r0, phi, Phi, gc, phic, gdotc = (x.ravel() for x in (f, r0, phi, Phi, gc, phic, gdotc))
        closed = self.closed_rows(gc, closed)
        approaching = closed[gdotc[closed] < -self.contact_tol]
        if approaching.size:
            i = int(approaching[0])
            raise InputError(
                f"contact {self.contact_row_names[i]!r} is closed and approaching (ġ = {gdotc[i]:.3g}) at t={t:.6g}: "
                "the velocities must jump first — apply model.impact(...) or simulate, which does"
            )
        if not np.all(np.isfinite(A)) or not np.all(np.isfinite(f + r0)):
            raise NonFiniteError(f"the mass matrix or the forces are not finite at t={t:.6g}; check the model there")
        try:
            a0 = np.linalg.solve(A, f + r0)
        except np.linalg.LinAlgError:
            a0 = np.zeros(self.nv)  # the QP's Cholesky reports the singular A
        m = self.m
        problem = self.gauss_problem(t, A, a0, J, phi, D, Jc, phic[closed], closed)
        sol = solve_general(
            problem,
            backend,
            consistency_tol,
            reference=lambda: self.reference_problem(t, q, v, lam, stab, closed),
            # a state on the constraints to REACH_TOL is itself the witness that dependent rows hold together
            near_manifold=self.k == 0 or self.off_manifold(J, Phi, g, q, v)[0] <= REACH_TOL,
        )
        u = sol.u[:m]
        contact_force = np.zeros(len(self.contact_row_names))
        contact_force[closed] = sol.u[m:]
        D2, J2 = D.reshape(self.nv, m), J.reshape(self.k, self.nv)
        cos = cosines(A, J2, D2) if self.k else np.zeros(0)
        margin = (float(cos.min()) if m >= self.k and cos.size else 0.0) if self.k else 1.0
        reaction = r0 + problem.D @ sol.u  # the realizations' reactions and the contact forces
        result = StepResult(
            t=t,
            a=sol.a,
            u=u,
            reaction=reaction,
            compulsion=sol.compulsion,
            margin=margin,
            cosines=cos,
            residual=sol.residual[: self.k],
            constraint_value=Phi,
            free_acceleration=np.linalg.solve(A, f),
            solver=f"gauss-qp:{check_backend(backend)}",
            contact_force=contact_force,
            tracking_error=sol.tracking_error,
            saturated=sol.at_bound[:m],
        )
        extras = {
            "qdot": qdot.ravel(),
            "energy": energy.ravel(),
            "power_forces": power.ravel(),
            "power_reaction": np.array([float(v @ reaction)]),
            "g": g.ravel(),
            "S_norm": sol.S_norm[: self.k, :m],
        }
        return result, sol, extras

    def reference_problem(
        self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: Any, closed: np.ndarray
    ) -> GaussProblem | None:
        """The step problem at the nearest state on the constraint manifold, where redundancy is decided.

        ``None`` when the state is on the manifold already (decide there). See :meth:`_nearest_on_manifold`.
        """
        q_ref, v_ref = self.nearest_on_manifold(t, q, v, lam)
        A, f, r0, J, phi, D, Phi, g, _qd, _e, _p, _gc, Jc, phic, _gdc = self.evaluate_data(t, q_ref, v_ref, lam, stab)
        self.check_reachable(t, J.reshape(self.k, self.nv), Phi.ravel(), g.ravel(), q_ref, v_ref)
        if np.array_equal(q_ref, q) and np.array_equal(v_ref, v):
            return None
        if not (np.all(np.isfinite(A)) and np.all(np.isfinite(f + r0))):
            return None
        try:
            a0 = np.linalg.solve(A, (f + r0).ravel())
        except np.linalg.LinAlgError:
            return None
        return self.gauss_problem(t, A, a0, J, phi, D, Jc, phic.ravel()[closed], closed)

    def off_manifold(
        self, J: np.ndarray, Phi: np.ndarray, g: np.ndarray, q: np.ndarray, v: np.ndarray
    ) -> tuple[float, int]:
        """How far the state is from the constraints, and the row farthest off.

        Each row's residual is a distance in coordinates (``|g_i| / ‖J_i‖``, ``|Φ_i| / ‖J_i‖``) relative to the
        state's size; compared with :data:`REACH_TOL`.
        """
        J = J.reshape(self.k, self.nv)
        norms = np.linalg.norm(J, axis=1)
        norms[norms == 0] = 1.0
        rows = self.holonomic_rows
        off = np.abs(Phi.ravel()) / norms / (1.0 + np.max(np.abs(v), initial=0.0))
        off[rows] = np.maximum(off[rows], np.abs(g.ravel()[rows]) / norms[rows] / (1.0 + np.max(np.abs(q))))
        worst = int(np.argmax(off)) if off.size else 0
        return (float(off[worst]) if off.size else 0.0), worst

    def check_reachable(
        self, t: float, J: np.ndarray, Phi: np.ndarray, g: np.ndarray, q: np.ndarray, v: np.ndarray
    ) -> None:
        """Raise if the nearest state found is not on the constraints: then they contradict each other."""
        size, worst = self.off_manifold(J, Phi, g, q, v)
        if size <= REACH_TOL:
            return
        raise RealizabilityError(
            f"the constraint rows of {', '.join(map(repr, self.names))} are dependent and contradict each other at "
            f"t={t:.6g}: no state near this one "
            f"satisfies them all (row {self.row_names[worst]!r} stays off by {size:.2g} relative to the state's size) "
            "— the redundant rows describe different constraints; remove one of them",
            t=t,
            constraint=self.row_names[worst],
            margin=0.0,
        )

    def nearest_on_manifold(
        self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, iterations: int = 8
    ) -> tuple[np.ndarray, np.ndarray]:
        """The state on the constraints nearest ``(q, v)``, moving along the realizations' directions ``A⁻¹D``.

        Gauss–Newton onto ``g(q, t) = 0`` (holonomic rows) in two phases: first with the rows that are clearly
        independent here (:data:`~gausspp.redundancy.CLEARLY_INDEPENDENT`, in the order declared: a square
        step on rows that are dependent on the manifold would be huge along their near-null direction), then
        with every row in least squares; then ``v`` onto ``Φ = 0`` (affine in ``v``: one least-squares step).
        Works with redundant rows, where the compiled projection (:func:`gausspp.simulation.drift.projection_function`)
        cannot.
        """
        if self._kinematics_fn is None:
            mech = self.mechanism
            self._kinematics_fn = ca.Function("K", [mech.t, mech.q, mech.v], [ca.jacobian(mech.qdot, mech.v)])
        rows, k, nv = self.holonomic_rows, self.k, self.nv
        cols = [c for grp in self.groups if grp.rows.start in rows for c in range(grp.cols.start, grp.cols.stop)]
        normalize = self.mechanism.normalize_array

        def correction(A: np.ndarray, J: np.ndarray, D: np.ndarray, residual: np.ndarray) -> np.ndarray:
            AinvD = np.linalg.solve(A, D)
            return AinvD @ np.linalg.lstsq(J @ AinvD, residual, rcond=1e-10)[0]

        q_ref = q.copy()
        for phase in ("clear", "all") if rows else ():
            previous = np.inf
            for _ in range(iterations):
                A, _f, _r0, J, _phi, D, _Phi, g, *_ = self.evaluate_data(t, q_ref, v, lam, _NO_STAB)
                J, g, D = J.reshape(k, nv)[rows], g.ravel()[rows], D.reshape(nv, self.m)[:, cols]
                use = np.arange(len(rows))
                if phase == "clear":
                    use, _ = independent_rows(np.linalg.solve(np.linalg.cholesky(A), J.T).T, CLEARLY_INDEPENDENT)
                size = float(np.max(np.abs(g[use]), initial=0.0))
                if not size < previous or size == 0.0:  # converged to round-off (or no longer converging)
                    break
                previous = size
                step = correction(A, J[use], D, g[use])
                q_ref = normalize(q_ref - np.array(self._kinematics_fn(t, q_ref, v)) @ step)
        A, _f, _r0, J, _phi, D, Phi, *_ = self.evaluate_data(t, q_ref, v, lam, _NO_STAB)
        Phi = Phi.ravel()
        v_ref = v - correction(A, J.reshape(k, nv), D.reshape(nv, self.m), Phi) if np.any(Phi) else v
        return q_ref, v_ref

    def step_data(self, t: float, q: Any, v: Any, lam: Any = None) -> StepProblem:
        """The step's ``A, f = F − h, r₀, J, φ, D, Φ`` as numbers (no checks on their values)."""
        t, q, v, lam = self.checked_state(t, q, v, lam)
        if self._data_fn is None:
            p = self.expressions
            self._data_fn = ca.Function("step_data", self.inputs, [p.A, p.f, p.r0, p.J, p.phi, p.D, p.Phi])
        A, f, r0, J, phi, D, Phi = (np.array(x) for x in self._data_fn(t, q, v, lam, _NO_STAB))
        return StepProblem(A=A, f=f.ravel(), r0=r0.ravel(), J=J, phi=phi.ravel(), D=D, Phi=Phi.ravel())

    def closed_rows(self, gc: np.ndarray, closed: Any) -> np.ndarray:
        """Contact rows taken as closed: those given, else those within ``contact_tol`` of zero."""
        return np.flatnonzero(gc <= self.contact_tol) if closed is None else np.asarray(closed, dtype=int)

    def gauss_problem(
        self,
        t: float,
        A: np.ndarray,
        a0: np.ndarray,
        J: np.ndarray,
        phi: np.ndarray,
        D: np.ndarray,
        Jc: np.ndarray,
        phi_c: np.ndarray,
        closed: np.ndarray,
    ) -> GaussProblem:
        """The bilateral rows (bounded ones tracked) and the closed contacts (``≥``, force ``≥ 0``) as one QP."""
        m, nc, nv = self.m, closed.size, self.nv
        Jcc = Jc[closed].reshape(nc, nv)
        lower, upper = np.full(m + nc, -np.inf), np.full(m + nc, np.inf)
        lower[m:] = 0.0
        kind = ["eq"] * self.k + ["ge"] * nc
        for grp, bounds in zip(self.groups, self.group_bounds, strict=True):
            if bounds is not None:
                lower[grp.cols], upper[grp.cols] = bounds
                kind[grp.rows] = ["track"] * (grp.rows.stop - grp.rows.start)
        return GaussProblem(
            A=A,
            a0=a0,
            D=np.hstack([D.reshape(nv, m), Jcc.T]),
            J=np.vstack([J.reshape(self.k, nv), Jcc]),
            phi=np.concatenate([phi.ravel(), phi_c]),
            kind=kind,
            lower=lower,
            upper=upper,
            rows=[*self.row_names, *(self.contact_row_names[i] for i in closed)],
            t=t,
        )

    def impact(
        self,
        t: float,
        q: Any,
        v: Any,
        lam: Any = None,
        *,
        backend: str | None = None,
        plastic: Any = (),
        closed: Any = None,
    ) -> ImpactResult:
        """The velocity jump when contacts close: Gauss's principle at the velocity level.

        The post-impact velocities minimize ``½(v⁺ − v⁻)ᵀA(v⁺ − v⁻)`` subject to the bilateral
        constraints (``Φ(q, v⁺, t) = 0``, impulses along their realizations' directions) and
        Newton's law on every closed contact (``|g| ≤ contact_tol``):
        ``ġ⁺ ≥ −e ġ⁻`` if it approaches (``ġ⁻ < 0``), ``ġ⁺ ≥ 0`` otherwise, with impulse
        ``Λ ≥ 0`` and ``Λ (ġ⁺ + e ġ⁻) = 0``. Contact rows listed in ``plastic`` use ``e = 0``.
        """
        t, q, v, lam = self.checked_state(t, q, v, lam)
        if self.bounded:
            raise InputError(
                "impacts with bounded actuators are not supported: a bounded force cannot deliver an impulse"
            )
        A, _f, _r0, J, _phi, D, Phi, *_, gc, Jc, _phic, gdotc = self.evaluate_data(t, q, v, lam, _NO_STAB)
        Phi, gc, gdotc = Phi.ravel(), gc.ravel(), gdotc.ravel()
        closed = self.closed_rows(gc, closed)
        e = self.restitution[closed].copy()
        e[np.isin(closed, np.asarray(plastic, dtype=int))] = 0.0
        m, nv = self.m, self.nv
        Jcc = Jc[closed].reshape(closed.size, nv)
        target = -e * np.minimum(gdotc[closed], 0.0)  # ġ⁺ ≥ target
        # the same problem one level down: v⁻ plays a₀, impulses play forces, the rows act on v⁺
        phi = J.reshape(self.k, nv) @ v - Phi
        problem = self.gauss_problem(t, A, v, J, phi, D, Jc, Jcc @ v - gdotc[closed] + target, closed)
        sol = solve_general(problem, backend)
        impulse = np.zeros(len(self.contact_row_names))
        impulse[closed] = sol.u[m:]
        lam_after = lam + sol.u[: self.m][self.lam_columns] if self.n_lam else lam
        return ImpactResult(
            t=t,
            v_before=v,
            v_after=sol.a,
            lam_after=lam_after,
            impulse=impulse,
            closed=closed,
            kinetic_energy_before=0.5 * float(v @ A @ v),
            kinetic_energy_after=0.5 * float(sol.a @ A @ sol.a),
        )

    def __repr__(self) -> str:
        cons = ", ".join(f"{n} ({c.realization.label})" for n, c in zip(self.names, self.constraints, strict=True))
        contacts = ", ".join(
            f"{n} (e={c.restitution:g})" for n, c in zip(self.contact_names, self.contacts, strict=True)
        )
        more = f"; contacts: {contacts}" if contacts else ""
        return f"Model({type(self.mechanism).__name__}, nq={self.nq}, nv={self.nv}, constraints: {cons}{more})"


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


def _backend_name(backend: str | qp.QPBackend | None) -> str | None:
    return backend.name if isinstance(backend, qp.QPBackend) else backend
