"""The model: a mechanism, its constraints and their realizations — what the user declared.

``Model`` assembles docs/theory.md §2's step ``A q̈ = F − h + r₀ + D u``, ``J q̈ = φ`` from a front
end and constraints (:mod:`gausspp.model.assembly`) and offers the checked entry points
(:meth:`Model.step`, :meth:`Model.general_step`, :meth:`Model.impact`), which the step layer
(:mod:`gausspp.step`) carries out. A model does not change after construction: setting an attribute
raises :class:`~gausspp.errors.FrozenModelError`. What is built from it on demand — compiled kernels,
bound functions, projections — lives in its workspace (:mod:`gausspp.workspace`), not in it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from ..errors import (
    FrozenModelError,
    InputError,
    MissingMultiplierError,
    NonFiniteError,
    RealizabilityError,
    ShapeError,
)
from ..step import data, servo_reach
from ..step import impact as impact_step
from ..step.data import NO_STAB, StepProblem
from ..step.equality import checked
from ..step.equality.kernel import Kernel
from ..step.equality.sparse import choose_route
from ..step.general import GaussSolution, general_step, manifold
from ..step.qp import QPBackend
from ..step.realizability import symmetric_by_construction
from ..step.results import ImpactResult, StepResult
from ..validation import flag, positive, short
from .assembly import assemble, assemble_contacts
from .constraints import Constraint, Unilateral
from .mechanism import Mechanism
from .scales import Scales, check_scales

SOLVERS = checked.SOLVERS


class Model:
    """A mechanical system with constraints, each kept by its chosen realization.

    Parameters
    ----------
    mechanism : Lagrangian, RigidBody or MassMatrix
        The unconstrained system.
    constraints : Constraint or sequence of Constraint
        Each with its realization (ideal by default); :class:`~gausspp.Unilateral` contacts are kept apart. An
        empty list is the free mechanism (its step is the free acceleration ``A⁻¹f``).
    margin_warn : float
        A step whose realizability margin is below this warns (:class:`RealizabilityWarning`).
    margin_error : float
        Below this the constraint is deemed unrealizable (:class:`RealizabilityError`).
    refine : bool
        One step of iterative refinement after each solve (default). It restores round-off
        accuracy where ``A`` is ill-conditioned and the constraints nearly fix the acceleration
        (``a = a₀ + A⁻¹Du`` cancels there); ``False`` shows each solver's raw answer.
    contact_tol : float
        A contact whose gap is within this of zero is closed.
    route : {"auto", "dense", "sparse"}
        How the compiled step eliminates the acceleration (:mod:`gausspp.step.equality.sparse`): ``"dense"`` in whitened
        reaction space (robust to a badly conditioned ``A``; O(k³) graph), ``"sparse"`` in the mechanism's
        own sparsity (linear in the number of bodies for chains and trees); ``"auto"`` picks by size and
        sparsity (:func:`gausspp.step.equality.sparse.choose_route`). The chosen one is ``model.route``.
    codegen : bool
        Run the compiled lane's step as C (:mod:`gausspp.c_code`): many times faster per step, after a
        compilation of seconds for a large model, kept on disk for the next process. Without a C compiler the
        step stays in casadi's virtual machine.
    scales : gp.Scales or dict, optional
        The size of some components' motion where the numbers cannot tell it (``gp.Scales(q=[...], v=[...])``,
        ``None`` entries derived): every tolerance of a run is measured against scales read from the machine at
        its start (:mod:`gausspp.model.run_scales`); a declared size replaces the one read.
    friction : gp.FrictionContact or list of them, optional
        Hard contacts with Coulomb friction (:mod:`gausspp.friction`): ``gp.simulate`` integrates them event by
        event (its friction lane, :func:`gausspp.simulate_friction`). Kept as ``model.friction`` (a tuple).

    Attributes
    ----------
    nq, nv : int
        Sizes of ``q`` and ``v``.
    k : int
        Number of constraint rows; ``m`` the number of reaction unknowns.
    n_lam : int
        Size of the ``λ`` state (0 unless a realization carries ``λ``).
    names, row_names : list of str
        One name per bilateral constraint, and per constraint row.
    contacts, contact_names, contact_row_names : the unilateral contacts, their names, their rows' names.
    bounded : bool
        True if some realization has bounds on its reaction (a bounded :class:`~gausspp.Force`).
    expressions, inputs, groups, group_bounds, holonomic_rows, lam_columns, contact_expressions, restitution
        The assembled step (:mod:`gausspp.model.assembly`), as the step layer reads it
        (:class:`gausspp.step.protocol.StepModel`).
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
        route: str = "auto",
        codegen: bool = False,
        scales: Scales | dict[str, Any] | None = None,
        friction: Any = (),
    ) -> None:
        if not isinstance(mechanism, Mechanism):
            raise InputError(f"mechanism must be a Lagrangian, RigidBody or MassMatrix, got {type(mechanism).__name__}")
        constraints = _constraint_list(constraints)
        margin_warn = positive("margin_warn", margin_warn)
        margin_error = positive("margin_error", margin_error, zero_ok=True)
        contact_tol = positive("contact_tol", contact_tol, zero_ok=True)
        if not margin_error < margin_warn:
            raise InputError(f"need 0 ≤ margin_error < margin_warn, got {margin_error} and {margin_warn}")
        all_names = [c.name if c.name is not None else f"constraint {i}" for i, c in enumerate(constraints)]
        if len(set(all_names)) != len(all_names):
            raise InputError(f"constraint names must be unique, got {all_names}")
        bilateral = [(c, n) for c, n in zip(constraints, all_names, strict=True) if not isinstance(c, Unilateral)]
        unilateral = [(c, n) for c, n in zip(constraints, all_names, strict=True) if isinstance(c, Unilateral)]
        self.mechanism = mechanism
        self.nq, self.nv = mechanism.nq, mechanism.nv
        self.constraints = tuple(c for c, _ in bilateral)
        self.names = [n for _, n in bilateral]
        self.contacts: tuple[Unilateral, ...] = tuple(c for c, _ in unilateral)
        self.contact_names = [n for _, n in unilateral]
        self.margin_warn, self.margin_error = margin_warn, margin_error
        self.refine = flag("Model", "refine", refine)
        self.contact_tol = float(contact_tol)
        a = assemble(mechanism, self.constraints, self.names)
        self.expressions, self.inputs, self.k, self.m, self.n_lam = a.expressions, a.inputs, a.k, a.m, a.n_lam
        #: the route asked for ("auto", "dense" or "sparse") and the one taken ("dense" or "sparse")
        self.route_requested = route
        self.route = choose_route(a.expressions, route)
        #: every reaction along its constraint's normal (D = Jᵀ): the normalized S is symmetric at every state
        self.symmetric_S = self.k == self.m and symmetric_by_construction(a.expressions.J, a.expressions.D)
        self.codegen = flag("Model", "codegen", codegen)
        self.row_names, self.lam_columns, self.groups, self.group_bounds = (
            a.row_names,
            a.lam_columns,
            a.groups,
            a.group_bounds,
        )
        self.holonomic_rows, self._lam0 = a.holonomic_rows, a.lam0
        c = assemble_contacts(mechanism, self.contacts, self.contact_names)
        self.contact_expressions, self.contact_rows = c.expressions, c.rows
        self.contact_row_names, self.restitution = c.row_names, c.restitution
        self.bounded = any(b is not None for b in self.group_bounds)
        self.has_energy = mechanism.energy is not None
        self.has_force_power = mechanism.F_nc is not None
        #: the sizes the model declares (:class:`~gausspp.Scales`); ``None``: every scale read from the run's start
        self.scales = check_scales(scales, self.nq, self.nv)
        self.friction = _friction_contacts(friction)
        self._sealed = True

    def __setattr__(self, name: str, value: Any) -> None:
        if getattr(self, "_sealed", False):
            raise FrozenModelError(
                f"a Model does not change after construction (tried to set {name!r}); build a new Model with the "
                "changed mechanism, constraints or options"
            )
        object.__setattr__(self, name, value)

    # -- sizes and symbols -------------------------------------------------------------------
    @property
    def lam(self) -> ca.SX:
        """The symbol of the ``λ`` state (an input of every compiled function)."""
        return self.inputs[3]

    @property
    def stab(self) -> ca.SX:
        """The symbol of the Baumgarte coefficients ``(α, β)`` (an input; zero for the exact step)."""
        return self.inputs[4]

    @property
    def lam0(self) -> np.ndarray | None:
        """Initial ``λ`` from the realizations (``None`` if one is missing; empty if no λ state)."""
        return None if self._lam0 is None else self._lam0.copy()

    # -- checked entry points ---------------------------------------------------------------
    def kernel(self, solver: str = "qp", backend: str | QPBackend | None = None, refine: bool | None = None) -> Kernel:
        """The compiled step for ``solver`` (and QP ``backend``), built on first use and kept.

        Its inputs are ``(t, q, v, lam, stab)`` (``stab`` = Baumgarte ``(α, β)``, zero for the exact
        step); write them into ``kernel.inputs`` and call ``kernel.evaluate()`` for the fastest
        possible step, or call ``kernel(t, q, v, lam, stab)``. ``refine`` overrides the model's
        ``refine`` (``False``: each solver's raw answer).
        """
        return checked.kernel_for(self, solver, backend, self.refine if refine is None else bool(refine))

    def checked_state(self, t: Any, q: Any, v: Any, lam: Any) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """``(t, q, v, λ)`` as numbers of the right sizes, finite; ``λ`` defaults to the realizations' ``lam0``."""
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
        backend: str | QPBackend | None = None,
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
        refine = self.refine if refine is None else refine if type(refine) is bool else flag("step", "refine", refine)
        fast = checked.checked_call(self, solver, backend, refine)
        if fast is not None:
            result = fast(t, q, v, lam)
            if result is not None:
                return result
        else:  # contacts, bounds or redundant rows: the compiled general step, if its flag is up
            result = checked.general_hot(self, t, q, v, lam, solver, backend)
            if result is not None:
                return result
        t, q, v, lam = self.checked_state(t, q, v, lam)
        try:
            return checked.checked_step(self, t, q, v, lam, solver, backend, refine)
        except RealizabilityError as exc:  # a servo the actuators reach only through higher derivatives: say so
            raise servo_reach.explain(self, exc, t, q, v) from None

    def general_step(
        self,
        t: float,
        q: Any,
        v: Any,
        lam: Any = None,
        *,
        backend: str | None = None,
        stab: Any = NO_STAB,
        closed: Any = None,
    ) -> tuple[StepResult, GaussSolution]:
        """The step by the general Gauss QP (:mod:`gausspp.step.general`): contacts, bounds, redundancy.

        A contact is *closed* when its gap is within ``contact_tol`` of zero (or when it is listed
        in ``closed``, indices of contact rows, as an event-driven simulation knows); closed contacts enter
        as ``g̈ ≥ 0`` with a force ``λ ≥ 0``. A closed contact that is still approaching
        (``ġ < −contact_tol``) needs an impact first (:meth:`impact`): that is an error here.
        ``backend`` is a QP backend name (see :func:`gausspp.qp.names`).

        Returns the :class:`StepResult` and the QP's own :class:`~gausspp.step.general.GaussSolution`.
        """
        t, q, v, lam = self.checked_state(t, q, v, lam)
        result, sol, _ = general_step.solve_at(
            self, t, q, v, lam, checked.backend_name(backend), stab=stab, closed=closed
        )
        return result, sol

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
        return impact_step.impact(self, t, q, v, lam, backend, plastic, closed)

    def step_data(self, t: float, q: Any, v: Any, lam: Any = None) -> StepProblem:
        """The step's ``A, f = F − h, r₀, J, φ, D, Φ`` as numbers (no checks on their values)."""
        return checked.step_problem(self, *self.checked_state(t, q, v, lam))

    def evaluate_data(
        self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: Any = NO_STAB
    ) -> StepProblem:
        """Everything the step reads at a state, as one :class:`~gausspp.step.data.StepProblem` (inputs unchecked)."""
        return data.evaluate(self, t, q, v, lam, stab)

    def nearest_on_manifold(
        self, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The state on the constraints nearest ``(q, v)``
        (:func:`gausspp.step.general.manifold.nearest_on_manifold`)."""
        return manifold.nearest_on_manifold(self, t, q, v, lam)

    def general_step_full(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        lam: np.ndarray,
        backend: str | None,
        stab: Any,
        closed: Any = None,
    ) -> tuple[StepResult, GaussSolution, dict[str, np.ndarray]]:
        """:meth:`general_step` on checked inputs, with what a simulation records.

        See :func:`gausspp.step.general.general_step.solve_at`.
        """
        return general_step.solve_at(self, t, q, v, lam, backend, stab=stab, closed=closed)

    def __repr__(self) -> str:
        cons = ", ".join(f"{n} ({c.realization.label})" for n, c in zip(self.names, self.constraints, strict=True))
        cons = cons or "none (free)"
        contacts = ", ".join(
            f"{n} (e={c.restitution:g})" for n, c in zip(self.contact_names, self.contacts, strict=True)
        )
        more = f"; contacts: {contacts}" if contacts else ""
        return f"Model({type(self.mechanism).__name__}, nq={self.nq}, nv={self.nv}, constraints: {cons}{more})"


def _constraint_list(constraints: Constraint | Sequence[Constraint]) -> list[Constraint]:
    """The constraints as a list (none: the free mechanism, the comparison every lesson starts from)."""
    if isinstance(constraints, Constraint):
        constraints = [constraints]
    if isinstance(constraints, (str, bytes)) or not isinstance(constraints, (list, tuple)):
        try:
            constraints = list(constraints)
        except TypeError:
            raise InputError(
                f"constraints must be a Constraint or a list of them, got {type(constraints).__name__}"
            ) from None
    constraints = list(constraints)
    for c in constraints:
        if type(c).__name__ == "FrictionContact":  # gausspp.friction sits above the model layer: named, not imported
            raise InputError(
                "a FrictionContact is not a model constraint: simulate the mechanism with its frictional contacts by "
                "gp.simulate_friction(mechanism, [contacts], q0, v0, t_end)"
            )
        if not isinstance(c, Constraint):
            raise InputError(f"constraints must be Constraint, Holonomic or Unilateral objects, got {type(c).__name__}")
    return constraints


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


def model_argument(owner: str, model: Any) -> None:
    """Refuse anything but a :class:`Model` as ``owner``'s model (a scene's name, a scene itself …)."""
    if not isinstance(model, Model):
        hint = " (a scene carries one: gp.scenes.get(name).model)"
        raise InputError(f"{owner}: model must be a gp.Model{hint}, got {short(model)}")


def _friction_contacts(friction: Any) -> tuple[Any, ...]:
    """``friction`` as a tuple of :class:`gausspp.FrictionContact` (none: empty), or an error naming the argument."""
    if friction is None or (not hasattr(friction, "gap") and hasattr(friction, "__len__") and len(friction) == 0):
        return ()
    from .friction_contact import as_contacts

    return tuple(as_contacts("Model: friction", friction))
