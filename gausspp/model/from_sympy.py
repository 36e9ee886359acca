"""``gp.from_sympy``: a ``sympy.physics.mechanics`` system as a gausspp model.

Gauss's principle needs the *unconstrained* equations ``A(q) u̇ = f(q, u, t)`` in all the speeds ``u``, with
the constraints kept apart (their realization decides the reaction). sympy gives:

* ``KanesMethod`` / ``System``: the equations are formed again with every speed independent and no constraint
  (``KanesMethod(frame, q, u, kd_eqs, bodies, loads)``), so ``A = Σ mᵢ ∂vᵢ/∂u ⋅ ∂vᵢ/∂u + …`` is Kane's full,
  symmetric mass matrix; the kinematics ``q̇ = K(q, u)`` come from ``kindiffdict()``; the configuration
  constraints become :class:`~gausspp.Holonomic`, the velocity constraints that are not derivatives of
  configuration constraints become :class:`~gausspp.Constraint` (``B(q) u + c(q, t) = 0``).
* ``LagrangesMethod``: ``A`` is the first ``n`` columns of ``mass_matrix`` (the rest, ``lam_coeffs``, is ``−J``
  and is not needed: ``J`` comes from the constraint expressions), ``f = forcing`` with ``Derivative(q, t)``
  read as the speed ``q̇``; holonomic constraints become ``Holonomic``, nonholonomic ones ``Constraint``.

sympy keeps a ``KanesMethod``'s inertial frame and constraints, and a ``LagrangesMethod``'s holonomic
constraints, only in private attributes (sympy 1.12–1.14); :func:`_kane_parts` and :func:`_lagrange_parts` read
them in one place each. A ``System`` exposes all of it publicly.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ..errors import BackendUnavailableError, InputError, UnknownNameError
from ..validation import number
from .constraints import Constraint, Holonomic
from .mechanism import MassMatrix
from .model import Model
from .realizations import Realization
from .sympy_energy import energy_parts
from .sympy_expr import matrix_to_casadi, to_casadi


@dataclass(frozen=True)
class SympyModel:
    """What :func:`from_sympy` returns.

    Attributes
    ----------
    model : Model
        The model (with no constraint when the system has none: the free mechanism).
    mechanism : MassMatrix
        ``A(q) u̇ = f(q, u, t)``, ``q̇ = K(q, u)``; ``q`` and ``v`` in the order of ``coordinates``/``speeds``.
    constraints : tuple of Constraint
        One per constraint row, named ``"holonomic[i]"`` and ``"nonholonomic[i]"``.
    coordinates, speeds : tuple of str
        sympy's names of ``q`` and ``u`` (``"q1"``, ``"u1"``; ``"q1'"`` for a ``LagrangesMethod``'s speeds).
    """

    model: Model
    mechanism: MassMatrix
    constraints: tuple[Constraint, ...]
    coordinates: tuple[str, ...]
    speeds: tuple[str, ...]


@dataclass
class _Parts:
    """The sympy pieces every source reduces to: ``A u̇ = f``, ``q̇ = K``, ``g = 0``, ``Φ = 0``."""

    q: list[Any]
    u: list[Any]
    mass: Any
    forcing: Any
    qdot: list[Any]
    holonomic: list[Any]
    velocity: list[Any]
    speed_names: list[str]
    extra_leaves: dict[Any, int] = field(default_factory=dict)  # sympy leaf → index of the speed it is


def from_sympy(
    source: Any,
    *,
    parameters: Mapping[Any, float] | None = None,
    realization: Realization | str | Mapping[str, Realization | str] | None = None,
    **model_options: Any,
) -> SympyModel:
    """A ``KanesMethod``, ``LagrangesMethod`` or ``System`` of ``sympy.physics.mechanics`` as a gausspp model.

    Parameters
    ----------
    source : KanesMethod, LagrangesMethod or System
        The system; a ``LagrangesMethod`` need not have formed its equations yet.
    parameters : mapping, optional
        Numbers for the constant symbols (masses, lengths, ``g`` …): ``{m: 1.0, l: 0.5}``, keyed by the sympy
        symbols or by their names (``{"m": 1.0}``, where one symbol of the system has that name).
    realization : Realization, str or mapping, optional
        How the constraints are kept: one realization for all, or ``{"nonholonomic[0]": gp.Force(...)}`` per
        constraint name (the others ideal). Default: ideal.
    **model_options
        Passed to :class:`~gausspp.Model` (``margin_warn``, ``route`` …).

    Returns
    -------
    SympyModel
        The model, its mechanism and constraints, and the coordinate and speed names.

    Raises
    ------
    BackendUnavailableError
        Without sympy (``pip install gausspp[sympy]``).
    InputError
        For another ``source``, a symbol without a value, a ``Derivative`` in the equations or a function
        casadi lacks (the message quotes the term); a name in ``parameters`` that no constant of the system has,
        or that several have.
    """
    me = _sympy_mechanics()
    parts = _parts(source, me)
    if parameters is not None and not isinstance(parameters, Mapping):
        raise InputError(f"from_sympy: parameters must map symbols to numbers, got {type(parameters).__name__}")
    t = _time(me)
    kd = {} if parts.extra_leaves else {qi.diff(t): k for qi, k in zip(parts.q, parts.qdot, strict=True)}
    energy = energy_parts(source, parts.u, kd, me)
    values = _parameter_values(parameters or {}, _constants(parts, energy, me))
    mechanism = _mechanism(parts, values, me, energy)
    names = tuple(str(getattr(qi, "func", qi)) for qi in parts.q)
    mechanism.coordinate_names, mechanism.velocity_names = names, tuple(parts.speed_names)  # names in results
    constraints = _constraints(parts, values, mechanism, me, realization)
    model = Model(mechanism, constraints, **model_options)
    return SympyModel(model, mechanism, tuple(constraints), names, tuple(parts.speed_names))


def _sympy_mechanics() -> Any:
    try:
        import sympy.physics.mechanics as me
    except ImportError:
        raise BackendUnavailableError("gp.from_sympy needs sympy: pip install 'gausspp[sympy]'") from None
    return me


def _parts(source: Any, me: Any) -> _Parts:
    if isinstance(source, me.KanesMethod):
        return _kane_parts(source, me)
    if isinstance(source, me.LagrangesMethod):
        return _lagrange_parts(source, me)
    if isinstance(source, me.System):
        return _system_parts(source, me)
    raise InputError(
        f"from_sympy: source must be a sympy.physics.mechanics KanesMethod, LagrangesMethod or System, "
        f"got {type(source).__name__}"
    )


def _free_equations(frame: Any, q: list[Any], u: list[Any], kdes: list[Any], bodies: Any, loads: Any, me: Any) -> Any:
    """Kane's equations with every speed independent and no constraint: the unconstrained ``A``, ``f``, ``K``."""
    free = me.KanesMethod(frame, q_ind=q, u_ind=u, kd_eqs=kdes, bodies=list(bodies), forcelist=list(loads))
    free.kanes_equations()
    return free


def _time(me: Any) -> Any:
    """sympy's time symbol: the argument of every dynamic symbol (``dynamicsymbols('x') = x(t)``)."""
    return me.dynamicsymbols("x").args[0]


def _unexposed(obj: Any, name: str, what: str) -> Any:
    """An attribute sympy keeps but does not expose publicly (``what`` it holds), or a clear error if a sympy
    release no longer has it."""
    import sympy

    if not hasattr(obj, name):
        raise InputError(
            f"from_sympy: sympy {sympy.__version__}'s {type(obj).__name__} no longer holds {what} where gausspp "
            f"reads it ({name}); build the model with sympy.physics.mechanics.System instead, or pin sympy 1.14"
        )
    return getattr(obj, name)


def _kane_parts(kane: Any, me: Any) -> _Parts:
    t = _time(me)
    q, u = list(kane.q), list(kane.u)
    kd = kane.kindiffdict()
    kdes = [qi.diff(t) - kd[qi.diff(t)] for qi in q]
    frame = _unexposed(kane, "_inertial", "the inertial frame")  # KanesMethod has no public accessor for it
    free = _free_equations(frame, q, u, kdes, kane.bodies or [], kane.loads or [], me)
    # the constraints as given: KanesMethod exposes them only through to_linearizer(), which refuses forcing
    # terms with derivatives of specified quantities; f_v = k_nh u + f_nh
    holonomic = list(_unexposed(kane, "_f_h", "the configuration constraints"))
    k_nh = _unexposed(kane, "_k_nh", "the velocity constraints' matrix")
    f_nh = _unexposed(kane, "_f_nh", "the velocity constraints' remainder")
    velocity = list(k_nh * type(k_nh)(u) + f_nh) if k_nh is not None and k_nh.rows else []
    return _kane_like(free, q, u, holonomic, velocity, t)


def _system_parts(system: Any, me: Any) -> _Parts:
    t = _time(me)
    q, u = list(system.q), list(system.u)
    loads = list(system.loads) + [load for actuator in system.actuators for load in actuator.to_loads()]
    free = _free_equations(system.frame, q, u, list(system.kdes), system.bodies, loads, me)
    kd = free.kindiffdict()
    velocity = [me.msubs(c, kd) for c in system.nonholonomic_constraints]
    return _kane_like(free, q, u, list(system.holonomic_constraints), velocity, t)


def _kane_like(free: Any, q: list[Any], u: list[Any], holonomic: list[Any], velocity: list[Any], t: Any) -> _Parts:
    kd = free.kindiffdict()
    qdot = [kd[qi.diff(t)] for qi in q]
    names = [str(getattr(ui, "func", ui)) for ui in u]
    return _Parts(q, u, free.mass_matrix, free.forcing, qdot, holonomic, velocity, names)


def _lagrange_parts(method: Any, me: Any) -> _Parts:
    t = _time(me)
    if method.eom is None:
        method.form_lagranges_equations()
    q = list(method.q)
    n = len(q)
    qd = [qi.diff(t) for qi in q]
    # LagrangesMethod keeps the configuration constraints as given only here (its public coneqs are differentiated)
    holonomic = list(_unexposed(method, "_hol_coneqs", "the configuration constraints"))
    velocity = list(method.coneqs[len(holonomic) :])  # the rows after the differentiated holonomic ones
    names = [f"{getattr(qi, 'func', qi)}'" for qi in q]
    leaves = {d: i for i, d in enumerate(qd)}
    return _Parts(q, qd, method.mass_matrix[:, :n], method.forcing, qd, holonomic, velocity, names, leaves)


def _constants(parts: _Parts, energy: tuple[Any, list[Any]] | None, me: Any) -> list[Any]:
    """The leaves that take a number: the symbols of the equations, constraints and energy (not the time), and the
    functions of time among them that are neither coordinates nor speeds."""
    from sympy import sympify
    from sympy.core.function import AppliedUndef

    exprs = [parts.mass, parts.forcing, *parts.qdot, *parts.holonomic, *parts.velocity]
    exprs += [] if energy is None else [energy[0], *energy[1]]
    known = {*parts.q, *parts.u, *parts.extra_leaves, _time(me)}
    found: set[Any] = set()
    for expr in map(sympify, exprs):
        found |= expr.free_symbols | expr.atoms(AppliedUndef)
    return sorted(found - known, key=str)


def _parameter_values(parameters: Mapping[Any, Any], constants: list[Any]) -> dict[Any, float]:
    """sympy leaf → number: a key that is a name (``"m"``) stands for the one constant of that name
    (:func:`_named`); a value that is no finite number, or a leaf given twice, is refused by name."""
    values: dict[Any, float] = {}
    for key, value in parameters.items():
        leaf = _named(key, constants) if isinstance(key, str) else key
        if leaf in values:
            raise InputError(
                f"from_sympy: parameter {leaf} is given twice (by its symbol and its name {key!r}); keep one"
            )
        values[leaf] = number(f"from_sympy: parameter {key} must be a finite number, got {value!r}", value)
    return values


def _named(key: str, constants: list[Any]) -> Any:
    """The constant whose name is ``key`` (``"F"`` or ``"F(t)"`` for a function of time ``F(t)``), or an error
    naming the key and the fix."""
    found = [c for c in constants if key in (str(c), str(getattr(c, "func", c)))]
    if len(found) == 1:
        return found[0]
    if not found:
        raise UnknownNameError(
            f"from_sympy: parameters names {key!r}, which is no constant of the system; its constants are "
            f"{[str(c) for c in constants]} (key parameters by these names or by the sympy symbols)"
        )
    raise InputError(
        f"from_sympy: parameters names {key!r}, which {len(found)} different symbols of the system are called "
        "(their assumptions differ); key it by the sympy symbol itself"
    )


def _leaves(parts: _Parts, values: dict[Any, float], q: Any, v: Any, t: Any, me: Any) -> dict[Any, Any]:
    """sympy leaf → casadi: the coordinates, the speeds (when ``v`` is given), the time and the parameters."""
    leaves: dict[Any, Any] = dict(values)
    leaves[_time(me)] = t
    leaves.update({qi: q[i] for i, qi in enumerate(parts.q)})
    if v is not None:
        leaves.update({ui: v[i] for i, ui in enumerate(parts.u)})
        leaves.update({leaf: v[i] for leaf, i in parts.extra_leaves.items()})
    return leaves


def _mechanism(parts: _Parts, values: dict[Any, float], me: Any, energy: tuple[Any, list[Any]] | None) -> MassMatrix:
    """``A u̇ = f``, ``q̇ = K``, with the energy and the non-conservative forces where they are known
    (:mod:`gausspp.model.sympy_energy`)."""
    identity = len(parts.q) == len(parts.u) and all(k == ui for k, ui in zip(parts.qdot, parts.u, strict=True))
    extra: dict[str, Any] = {}
    if energy is not None:
        total, forces = energy
        extra = dict(
            energy=lambda q, v, t: to_casadi(total, _leaves(parts, values, q, v, t, me)),
            nonconservative=lambda q, v, t: matrix_to_casadi(forces, _leaves(parts, values, q, v, t, me)),
        )

    def A(q: Any, t: Any) -> ca.SX:
        return matrix_to_casadi(parts.mass, _leaves(parts, values, q, None, t, me))

    def f(q: Any, v: Any, t: Any) -> ca.SX:
        return matrix_to_casadi(parts.forcing, _leaves(parts, values, q, v, t, me))

    def kinematics(q: Any, v: Any, t: Any) -> ca.SX:
        return matrix_to_casadi(parts.qdot, _leaves(parts, values, q, v, t, me))

    try:
        if identity:
            return MassMatrix(len(parts.u), A, f, **extra)
        return MassMatrix(len(parts.u), A, f, kinematics=kinematics, nq=len(parts.q), **extra)
    except InputError:
        if not extra:
            raise
    # an energy term casadi could not take (a symbol sympy left in it): the model without its energy, as before
    if identity:
        return MassMatrix(len(parts.u), A, f)
    return MassMatrix(len(parts.u), A, f, kinematics=kinematics, nq=len(parts.q))


def _constraints(
    parts: _Parts, values: dict[Any, float], mech: MassMatrix, me: Any, realization: Any
) -> list[Constraint]:
    """One :class:`Holonomic` per configuration constraint, one :class:`Constraint` per independent velocity row."""
    out: list[Constraint] = []
    for i, g in enumerate(parts.holonomic):
        name = f"holonomic[{i}]"
        out.append(Holonomic(_holonomic_fn(parts, values, g, me), name=name, realization=_pick(realization, name)))
    rows = _new_velocity_rows(parts, values, mech, me)
    for i, row in enumerate(rows):
        name = f"nonholonomic[{i}]"
        fn = _velocity_fn(parts, values, parts.velocity[row], me)
        out.append(Constraint(fn, name=name, realization=_pick(realization, name)))
    unknown = sorted(set(realization) - {c.name for c in out}) if isinstance(realization, Mapping) else []
    if unknown:
        raise InputError(
            f"from_sympy: realization names {unknown} match no constraint; the constraints are {[c.name for c in out]}"
        )
    return out


def _holonomic_fn(parts: _Parts, values: dict[Any, float], g: Any, me: Any) -> Any:
    return lambda q, t: to_casadi(g, _leaves(parts, values, q, None, t, me))


def _velocity_fn(parts: _Parts, values: dict[Any, float], phi: Any, me: Any) -> Any:
    return lambda q, v, t: to_casadi(phi, _leaves(parts, values, q, v, t, me))


def _pick(realization: Any, name: str) -> Any:
    if isinstance(realization, Mapping):
        return realization.get(name)
    return realization


def _new_velocity_rows(parts: _Parts, values: dict[Any, float], mech: MassMatrix, me: Any) -> list[int]:
    """The velocity constraints not implied by the configuration constraints (Kane lists ``ġ = 0`` among them).

    Greedy on the rank of ``[∂g/∂q K; B_selected]`` at a generic state (a seeded random point): a row is kept
    when it adds to the rank, so for a ``System`` or ``LagrangesMethod`` (whose velocity rows are nonholonomic
    only) every independent row is kept.
    """
    if not parts.velocity:
        return []
    leaves = _leaves(parts, values, mech.q, mech.v, mech.t, me)
    g = matrix_to_casadi(parts.holonomic, _leaves(parts, values, mech.q, None, mech.t, me))
    B = ca.jacobian(matrix_to_casadi(parts.velocity, leaves), mech.v)
    G = ca.jacobian(ca.jacobian(g, mech.q) @ mech.qdot, mech.v) if g.numel() else ca.SX(0, mech.nv)
    point = np.random.default_rng(20).uniform(0.2, 0.9, mech.nq + mech.nv)
    matrices = ca.Function("velocity_rows", [mech.q, mech.v, mech.t], [G, B])
    G_num, B_num = (np.array(m) for m in matrices(point[: mech.nq], point[mech.nq :], 0.3))
    kept: list[int] = []
    for i in range(B_num.shape[0]):
        trial = np.vstack([G_num, B_num[kept + [i]]])
        if np.linalg.matrix_rank(trial) == trial.shape[0]:
            kept.append(i)
    return kept
