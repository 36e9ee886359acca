"""How the actuators reach a servo-constraint: relative degrees, dynamic extension, Blajer's geometry, the index.

The one-step formula needs ``S = J A⁻¹ D`` nonsingular (condition (12)): every actuator acts on the constrained
quantities' *accelerations*. Many machines are not like that. An overhead crane's trolley force reaches the
payload only through the rope's swing — in the payload's fourth derivative — and ``S`` is singular at every
state, although the motion along a prescribed path exists and is unique. This module measures the reach.

**Relative degree.** With the constraint's value ``y = g(q, t)`` (a holonomic row; ``Φ(q, v, t)`` for a row
given on velocities) and the dynamics ``q̇ = K(q, v, t)``, ``A v̇ = f + r₀ + D u``, differentiate along the
motion, ``y⁽ʲ⁾ = L y⁽ʲ⁻¹⁾`` with ``L h = ∂h/∂q q̇ + ∂h/∂v v̇ + ∂h/∂t``. Row ``i``'s relative degree ``rᵢ`` is
the first ``j`` at which an actuator force ``u`` appears: ``∂yᵢ⁽ʲ⁾/∂u ≠ 0``. (A dependence that vanishes at
the state and at nearby states is taken as identically zero — the tangential structure — and dropped before the
next derivative.) For a realizable servo every ``rᵢ = 2`` and the matrix of the ``∂yᵢ⁽ʳⁱ⁾/∂u`` is ``S``.

**Dynamic extension.** When that *decoupling matrix* ``B`` is singular (the crane: the rope tension reaches both
payload coordinates at ``r = 2``, the trolley force neither), the actuators that appear are delayed by an
integrator — their force becomes a state, its derivative the new input — and the degrees are measured again
(the simplest form of Descusse and Moog's extension algorithm). The crane needs two integrators on the
tension; then ``r = (4, 4)`` and ``B`` is nonsingular.

**Index and geometry.** The servo DAE's differentiation index is ``max rᵢ + 1`` after extension (``2n + 1`` for a
chain of ``n`` masses driven at one end and prescribed at the other). Blajer's geometries (:func:`geometry`), from the
principal angles between the constraint normals and the reaction directions in the kinetic metric:
*orthogonal* (all 0: the actuators push along the normals, an ideal constraint), *oblique* (none 90°),
*tangential* (all 90°: ``J A⁻¹ D = 0``, no actuator acts on the constrained accelerations) and *mixed*
(some 90°: the crane).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from scipy.linalg import orth, svdvals

from ..errors import InputError, RealizabilityError
from .protocol import StepModel

#: Dependence of a derivative on the inputs below this (relative to its dependence on the state) counts as none.
REACH_TOL = 1e-9

#: A cosine below this counts as zero when the geometry is named.
KIND_TOL = 1e-9


@dataclass(frozen=True)
class ReachSizes:
    """The sizes the reach test weighs each sensitivity by, so that it means the same in any units.

    Whether ``h`` depends on an input ``w_a`` is read from ``|∂h/∂w_a| S_w,a`` against the largest
    ``|∂h/∂z_j| S_z,j`` (and ``|∂h/∂t| τ``): every term in the units of ``h``. ``q``, ``v``: each coordinate's and
    velocity component's size; ``force``: each actuator's; ``time``: the motion's time scale ``τ`` — the ``j``-th
    derivative of an actuator's force is sized ``S_u / τʲ``. gp.simulate passes the run's sizes
    (:func:`gausspp.model.reach_sizes.reach_sizes`); :func:`state_sizes` is the fallback."""

    q: np.ndarray
    v: np.ndarray
    force: np.ndarray
    time: float

    def state(self, chains: tuple[int, ...]) -> np.ndarray:
        """The sizes of the extended state ``z = (q, v, ξ)``."""
        xi = [self.force[a] / self.time**j for a, c in enumerate(chains) for j in range(c)]
        return np.concatenate([self.q, self.v, np.asarray(xi, float)])

    def inputs(self, chains: tuple[int, ...]) -> np.ndarray:
        """The sizes of the inputs ``w``: a force, or the ``c``-th derivative of one behind ``c`` integrators."""
        return np.array([self.force[a] / self.time**c for a, c in enumerate(chains)], float)


def state_sizes(model: StepModel, q: np.ndarray, v: np.ndarray) -> ReachSizes:
    """The sizes when the run's are not known: each component's own, at least 1 in the model's units, and 1 for a
    force and for the time scale — good in SI-like units; gp.simulate passes the run's sizes, which hold in any."""
    return ReachSizes(np.maximum(1.0, np.abs(q)), np.maximum(1.0, np.abs(v)), np.ones(model.m), 1.0)


@dataclass
class Extended:
    """The motion's symbols and derivatives with some actuators delayed by integrators.

    ``z = (q, v, ξ)`` with ``ξ`` the chains ``(uₐ, u̇ₐ, …)`` of the extended actuators; ``w`` the inputs: the
    forces of the others and the top derivative of each chain; ``zdot`` the motion ``ż(z, w, t)``."""

    t: ca.SX
    z: ca.SX
    w: ca.SX
    zdot: ca.SX
    force: ca.SX  # the m actuator forces in terms of z and w
    chains: tuple[int, ...]  # integrators per actuator


def extended_motion(model: StepModel, chains: tuple[int, ...]) -> Extended:
    """The model's motion with ``chains[a]`` integrators in front of actuator ``a`` (0: a force as input)."""
    p = model.expressions
    t, q, v, lam, stab = model.inputs
    if lam.numel() or not model.m:
        raise InputError("index reduction needs actuator forces and no realization that carries λ as a state")
    xi = [ca.SX.sym(f"xi{a}", c) for a, c in enumerate(chains)]
    w = ca.SX.sym("w", len(chains))
    force = ca.vertcat(*[xi[a][0] if c else w[a] for a, c in enumerate(chains)])
    rhs = ca.substitute(p.f + p.r0, stab, ca.SX.zeros(stab.shape))
    D = ca.substitute(p.D, stab, ca.SX.zeros(stab.shape))
    vdot = ca.solve(p.A, rhs + D @ force)
    xidot = [ca.vertcat(*[xi[a][j] for j in range(1, c)], w[a]) for a, c in enumerate(chains) if c]
    qdot = p.qdot if p.qdot is not None else v
    z = ca.vertcat(q, v, *[x for x in xi if x.numel()])
    zdot = ca.vertcat(qdot, vdot, *xidot)
    return Extended(t, z, w, ca.substitute(zdot, stab, ca.SX.zeros(stab.shape)), force, chains)


def outputs(model: StepModel) -> ca.SX:
    """The constrained quantities ``y``: ``g(q, t)`` for holonomic rows, ``Φ(q, v, t)`` for the others."""
    p = model.expressions
    g = p.g if p.g is not None else p.Phi
    rows = [g[i] if i in model.holonomic_rows else p.Phi[i] for i in range(model.k)]
    stab = model.inputs[4]
    return ca.substitute(ca.vertcat(*rows), stab, ca.SX.zeros(stab.shape))


def lie(h: ca.SX, e: Extended) -> ca.SX:
    """``dh/dt`` along the extended motion (common subexpressions merged: each derivative repeats much of the
    last, and without the merge the twelfth derivative of a six-mass chain has ~10⁶ nodes instead of ~10³)."""
    return ca.cse(ca.jtimes(h, e.z, e.zdot) + ca.jacobian(h, e.t))


@dataclass
class Reach:
    """The derivatives of the constrained quantities down to where the inputs appear (see the module docstring)."""

    extended: Extended
    degrees: tuple[int, ...]  # relative degree of each row
    derivatives: list[list[ca.SX]]  # derivatives[i][j] = yᵢ⁽ʲ⁾ for j < rᵢ (input-free), and yᵢ⁽ʳⁱ⁾ (affine in w)
    B: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # ∂y⁽ʳ⁾/∂w at the state
    unextended: tuple[int, ...] = ()  # the relative degrees before any integrator was added
    sizes: np.ndarray = field(default_factory=lambda: np.zeros(0))  # each yᵢ⁽ʳⁱ⁾'s size, S_yᵢ / τ^rᵢ

    @property
    def index(self) -> int:
        """The differentiation index of the servo DAE: ``max rᵢ + 1``."""
        return max(self.degrees) + 1


def _states_near(z0: np.ndarray, size: np.ndarray, count: int = 3) -> list[np.ndarray]:
    """``z0`` and generic states around it, a tenth of each component's ``size`` away: structure (which input
    reaches which derivative, the rank of ``B``) is a property of the equations, not of one state — a crane at rest
    with zero tension would hide it."""
    rng = np.random.default_rng(1989)  # the paper's year: any fixed seed
    return [z0] + [z0 + 0.1 * size * rng.standard_normal(z0.size) for _ in range(count)]


def _reaches(
    expr: ca.SX, e: Extended, t0: float, states: list[np.ndarray], sizes: ReachSizes, floor: float
) -> np.ndarray:
    """Which inputs ``expr`` depends on at the states: ``|∂h/∂w_a| S_w,a`` against the largest term of its
    linearization — in the inputs, the state and time, each weighed by its size (:class:`ReachSizes`) — and at least
    ``floor``, the derivative's own size: a dependence at round-off of the others, or of the motion, is none."""
    grad = ca.Function(
        "grad", [e.t, e.z, e.w], [ca.jacobian(expr, e.w), ca.jacobian(expr, e.z), ca.jacobian(expr, e.t)]
    )
    size_z, size_w = sizes.state(e.chains), sizes.inputs(e.chains)
    hit = np.zeros(e.w.numel(), dtype=bool)
    for z in states:
        dw, dz, dt = (np.array(x, dtype=float).ravel() for x in grad(t0, z, np.zeros(e.w.numel())))
        terms = np.abs(dw) * size_w
        state_terms = max(np.max(np.abs(dz) * size_z, initial=0.0), np.abs(dt).sum() * sizes.time)
        largest = max(terms.max(initial=0.0), state_terms, floor)
        hit |= terms > REACH_TOL * largest
    return hit


def _size(y: ca.SX, e: Extended, t0: float, states: list[np.ndarray], sizes: ReachSizes) -> float:
    """The size of a constrained quantity: the terms of its linearization in the state and time, each weighed by its
    size, the largest over the states (its ``j``-th derivative is sized this over ``τʲ``)."""
    grad = ca.Function("size", [e.t, e.z], [ca.jacobian(y, e.z), ca.jacobian(y, e.t)])
    size_z = sizes.state(e.chains)
    largest = 0.0
    for z in states:
        dz, dt = (np.array(x, dtype=float).ravel() for x in grad(t0, z))
        largest = max(largest, float(np.abs(dz) @ size_z + np.abs(dt).sum() * sizes.time))
    return largest


def measure_reach(
    model: StepModel, t0: float, z0: np.ndarray, chains: tuple[int, ...], max_degree: int, sizes: ReachSizes
) -> Reach:
    """The relative degrees and derivatives with ``chains`` integrators (``z0``: the extended state)."""
    e = extended_motion(model, chains)
    y = outputs(model)
    states = _states_near(np.asarray(z0, float), sizes.state(chains))
    degrees, derivatives, top_sizes = [], [], []
    for i in range(y.numel()):
        chain, h = [], y[i]
        size_y = _size(y[i], e, t0, states, sizes)
        for _ in range(max_degree):
            chain.append(h)
            h = lie(h, e)
            hit = _reaches(h, e, t0, states, sizes, size_y / sizes.time ** len(chain))
            if hit.any():
                break
            h = ca.substitute(h, e.w, ca.SX.zeros(e.w.shape))  # a vanishing dependence: none at all
        else:
            raise InputError(
                f"no actuator reaches constraint row {model.row_names[i]!r} within {max_degree} derivatives: "
                "the servo cannot keep it with these actuators"
            )
        degrees.append(len(chain))
        top_sizes.append(size_y / sizes.time ** len(chain))
        derivatives.append([*chain, h])
    top = ca.vertcat(*[d[-1] for d in derivatives])
    B_of = ca.Function("B", [e.t, e.z, e.w], [ca.jacobian(top, e.w)])
    candidates = [np.array(B_of(t0, z, np.zeros(e.w.numel()))) for z in states]
    size_w = sizes.inputs(chains)
    row_sizes = np.array(top_sizes)
    B = max(candidates, key=lambda B: _conditioning(_weighed(B, size_w, row_sizes)))  # the generic rank
    return Reach(e, tuple(degrees), derivatives, B, sizes=row_sizes)


def _weighed(B: np.ndarray, size_w: np.ndarray, row_sizes: np.ndarray) -> np.ndarray:
    """``B`` with each input's column times its size and each row (a derivative in its own units) scaled to a
    largest entry of 1, or divided by the derivative's size where that is larger: the same numbers in any units,
    and a row at round-off of its size stays at round-off."""
    W = B * size_w[None, :]
    rows = np.maximum(np.abs(W).max(axis=1, initial=0.0), row_sizes)
    return W / np.where(rows > 0, rows, 1.0)[:, None]


def _conditioning(B: np.ndarray) -> float:
    """``σ_min / σ_max`` of a square ``B`` (0 if it is not square or is zero)."""
    if B.shape[0] != B.shape[1] or not B.size:
        return 0.0
    sv = np.linalg.svd(B, compute_uv=False)
    return float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0


def find_reach(
    model: StepModel,
    t0: float,
    q0: np.ndarray,
    v0: np.ndarray,
    max_extensions: int = 8,
    sizes: ReachSizes | None = None,
) -> Reach:
    """The relative degrees, extending the actuators that appear while the decoupling matrix is singular
    (``sizes``: the run's, :class:`ReachSizes`; by default :func:`state_sizes`)."""
    sizes = sizes if sizes is not None else state_sizes(model, q0, v0)
    n_state = model.nq + model.nv
    chains = tuple(0 for _ in range(model.m))
    unextended: tuple[int, ...] = ()
    for _ in range(max_extensions + 1):
        xi0 = np.zeros(sum(chains))
        z0 = np.concatenate([q0, v0, xi0])
        reach = measure_reach(model, t0, z0, chains, 2 * n_state + 2 * sum(chains) + 2, sizes)
        unextended = unextended or reach.degrees
        weighed = _weighed(reach.B, sizes.inputs(chains), reach.sizes)
        if _conditioning(weighed) > REACH_TOL:
            reach.unextended = unextended
            return reach
        appear = np.abs(weighed).max(axis=0) > REACH_TOL
        if not appear.any():
            break
        chains = tuple(c + 1 if hit else c for c, hit in zip(chains, appear, strict=True))
    raise InputError(
        "the actuators cannot be decoupled along this constraint (the decoupling matrix stays singular after "
        f"{max_extensions} integrators): the servo problem has no unique solution with these actuators"
    )


def geometry(model: StepModel, A: np.ndarray, J: np.ndarray, D: np.ndarray) -> str:
    """Blajer's name for the realization, from the principal angles (in the kinetic metric ``A⁻¹``) between the
    constraint normals ``Jᵀ`` and the reaction directions ``D``: *orthogonal* (the same subspace: every angle
    0, an ideal constraint), *tangential* (perpendicular: every angle 90°, ``J A⁻¹ D = 0``), *mixed* (some at
    90°) or *oblique* (none)."""
    if not (J.size and D.size):
        return "tangential"
    L = np.linalg.cholesky(A)  # A⁻¹ = L⁻ᵀ L⁻¹: the metric's inner product is that of L⁻¹x and L⁻¹y
    # cosines of the principal angles: singular values of the product of orthonormal bases (accurate near 90°,
    # where scipy's subspace_angles, going through the angle, keeps only √ε)
    cos = svdvals(orth(np.linalg.solve(L, J.T)).T @ orth(np.linalg.solve(L, D)))
    right = cos <= KIND_TOL
    if right.all():
        return "tangential"
    if right.any() or cos.size < min(J.shape[0], D.shape[1]):
        return "mixed"
    return "orthogonal" if np.all(1.0 - cos <= 1e-9) and J.shape[0] == D.shape[1] else "oblique"


def evaluate_J(model: StepModel, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The constraint Jacobian ``J`` at the state (numbers)."""
    t_, q_, v_, lam, stab = model.inputs
    fn = ca.Function("J", [t_, q_, v_, lam, stab], [model.expressions.J])
    return np.array(fn(t, q, v, np.zeros(lam.numel()), np.zeros(stab.numel())), float)


def actuators_only(model: StepModel) -> bool:
    """Rows kept by actuators alone (force realizations, as many as rows, no λ, no contacts or bounds): the only
    models whose constraint can be out of the one-step solution's reach."""
    return bool(
        model.k
        and not model.n_lam
        and model.m == model.k
        and not model.contacts
        and not model.bounded
        and all(g.label == "force" for g in model.groups)
    )


def higher_reach(model: StepModel, t: float, q: Any, v: Any, sizes: ReachSizes | None = None) -> Reach | None:
    """How the actuators reach the constraint when only its higher derivatives feel them (index above 3, or
    integrators needed in front of an actuator); ``None`` where the one-step solution is the one (or nothing
    reaches): only actuators (force realizations, as many as rows, no λ, no contacts or bounds) can be out of
    reach — rows of other realizations that fail are dependent rows or directions."""
    if not actuators_only(model):
        return None
    q, v = np.asarray(q, float), np.asarray(v, float)
    J = evaluate_J(model, t, q, v)
    norms = np.linalg.norm(J, axis=1)
    if np.linalg.matrix_rank(J / np.where(norms > 0, norms, 1.0)[:, None]) < model.k:  # redundant rows, not reach
        return None
    try:
        reach = find_reach(model, t, q, v, max_extensions=4, sizes=sizes)
    except (InputError, RuntimeError):  # no actuator reaches it
        return None
    return None if reach.index <= 3 and not any(reach.extended.chains) else reach


def explain(model: StepModel, exc: RealizabilityError, t: float, q: Any, v: Any) -> RealizabilityError:
    """The one-step solution's refusal ``exc``, reworded when the actuators do reach the constraint through a higher
    derivative: then the advice is index reduction, not other actuators. Anything else is returned unchanged."""
    reach = higher_reach(model, t, q, v)
    if reach is None:
        return exc
    degrees = ", ".join(f"{r!r}: {d}" for r, d in zip(model.row_names, reach.degrees, strict=True))
    extension = " (with integrators in front of some actuators)" if any(reach.extended.chains) else ""
    names = ", ".join(repr(n) for n in model.names)
    return RealizabilityError(
        f"constraint(s) {names} cannot be kept step by step at t={t:.6g}: J A⁻¹ D is singular, yet the actuators "
        f"reach the constraint through higher derivatives — relative degrees {degrees}{extension}, a servo DAE of "
        f"index {reach.index}. This is not a wrong choice of actuators: follow the constraint with "
        "gp.simulate_servo (index reduction); gp.servo_diagnosis tells how each actuator reaches it",
        t=t,
        constraint=", ".join(model.names),
        margin=exc.margin,
    )
