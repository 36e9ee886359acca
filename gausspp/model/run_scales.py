"""The scales every tolerance of a run is measured against (docs/guide.md, "The scales of a run").

A tolerance is a number without units: a residual, an error or an energy balance is compared with a *scale* of
the same units. A scale must mean the same at rest and in motion, in metres and in millimetres, so it is built
from the machine itself — never the number 1 (which has units, and mixes them), never the largest coordinate of
the whole state (which has nothing to do with a row that does not depend on it), never only what vanishes at rest
(the kinetic energy, the work exchanged). Four scales, all in the units of what they judge:

* **The motion's size of each component** ``S`` (:attr:`RunScales.q`, ``v``, ``lam``), read at the start:
  ``S_q = |q₀|``, ``S_v = |v₀| + √(|q̈₀| S_q)`` (the speed a harmonic motion released from ``q₀`` with
  acceleration ``q̈₀`` reaches: ``ω X = √(ω² X · X)``), ``S_λ = |λ₀|``. An adaptive run's default absolute tolerance
  is ``ATOL_SHARE·rtol·S`` on each component, so a pendulum released 1e-9 rad from rest is followed to ``rtol`` of *its*
  motion, and a machine rewritten in millimetres takes the same steps.
* **The machine's round-off floor** ``M`` of each component: what double precision cannot resolve in this machine.
  Coordinates are compared in the kinetic metric, so that a length and an angle are weighed by the inertia that
  moves with them: ``M_q,j = √(K_q / A_jj)`` with ``K_q = maxᵢ A_ii |q_i|²``; velocities by the machine's energy
  ``Ẽ`` (the work of its forces over the coordinates' sizes plus its kinetic energy,
  ``Σ_j |F_j| max(|q_j|, M_q,j) + ½ v₀ᵀAv₀``; ``2 m g L`` for a pendulum hanging at rest):
  ``M_v,j = √(2 Ẽ / A_jj)``. The maxima and sums run over the *part* of the machine the component belongs to — the
  components joined through the mass matrix, a constraint row or a force (:func:`structure`) — so that a free
  coordinate far away never enters another part's scales. A part all of whose coordinates start at zero takes
  ``K_q = 2 T₀ (t_end − t₀)²``, the way its motion goes in the run; at rest ``max_j F_j² (t_end − t₀)⁴ / A_jj``, the
  way its forces would take it; else ``max_j A_jj r_j²`` with ``r`` how far a prescribed target takes it.
  The absolute tolerance is never below ``ROUNDOFF·M`` (else a component at rest, whose error estimate is the
  round-off of its forces, would shrink the step to nothing), and a recorded residual or energy balance within
  ``CHECK_ROUNDOFF`` of its floor is round-off, whatever the tolerance; the floors grow with the time elapsed, as
  round-off accumulates (``a_j = |F_j| / A_jj``: ``M_v + a (t − t₀)``, ``M_q + M_v (t − t₀) + a (t − t₀)²``).
  A component that starts at zero (to round-off) has no size of its own: it takes the machine's along the motions
  the constraints allow, ``√(K_q c_j)`` and ``√(2 Ẽ c_j)`` with ``c_j`` the diagonal of the constrained mobility
  ``A⁻¹ − A⁻¹Jᵀ(JA⁻¹Jᵀ)⁺JA⁻¹`` (a pendulum's angle moves with ``m L² + I_c``, not with its body's ``I_c`` alone: a
  metre of arm gives it a radian). A component the rows hold has none (its tolerance is the round-off floor alone);
  one they hold only at this instant (a pendulum's ``x`` with its arm level) takes ``1/A_jj`` for ``c_j``.
* **Each constraint row's own scale**: ``Σ_j |∂g_i/∂q_j| · max(|q_j|, S_q,j)`` for its position residual and
  ``Σ_j |J_ij| · max(|v_j|, S_v,j)`` for its velocity residual — the size of the terms the row adds up (its
  round-off), over the run (:func:`row_scales`) — and at least how far its explicit time terms move in the run
  (``max_t |g(q₀, t) − g(q₀, t₀)|``: a prescribed target's excursion). A coordinate the row does not depend on
  does not enter it.
* **The energy scale** (:func:`energy_scale`): the energies that enter the balance ``E − E₀ = W_R + W_F`` — the
  largest kinetic energy, the potential's range over the run (``max V − min V``: not its value, whose zero is
  arbitrary), the works and the exchanges — with the round-off floor ``CHECK_ROUNDOFF·(|E|, T, |V| reached +
  Σ_j |F_j| M_q,j(t))``: a machine at rest still has its weight times its size.

Where numbers alone cannot tell a model's scales (a machine at rest at the origin with no force, a coordinate that
starts at zero but will move far), the model may declare them: ``gp.Model(..., scales=gp.Scales(q=..., v=...))``
replaces the derived sizes and floors of the components it names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from ..workspace import workspace

if TYPE_CHECKING:
    from .model import Model

EPS = float(np.finfo(float).eps)
#: An adaptive step's absolute tolerance is never below this times the machine's round-off floor ``M``.
ROUNDOFF = 4.0 * EPS
#: A residual or an energy balance within this times its floor is round-off, not drift (a run of many steps adds
#: up that many roundings: 1e4 ε ≈ 2e-12 of the machine's size).
CHECK_ROUNDOFF = 1e4 * EPS
#: Row sensitivities are read at up to this many samples, spread over the run.
SENSITIVITY_SAMPLES = 64
#: An adaptive step's absolute tolerance is this times ``rtol`` times each component's size: the error where a
#: component passes through zero is a tenth of the error ``rtol`` admits at its largest.
ATOL_SHARE = 0.1
#: The smallest positive scale: a component that no force moves and that starts at zero stays at zero exactly.
TINY = float(np.finfo(float).tiny)


@dataclass(frozen=True)
class RunScales:
    """The scales of one run, read at its initial state (module docstring)."""

    #: the motion's size of each coordinate, velocity and state ``λ``
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    #: the machine's round-off floor of each coordinate and velocity, and the acceleration of each component's
    #: forces (how fast the floors grow)
    floor_q: np.ndarray
    floor_v: np.ndarray
    accel: np.ndarray
    #: the floor of the displacement along each velocity component (``floor_q`` where ``nq = nv``)
    floor_dq: np.ndarray
    #: the size of each generalized force ``|F_j|`` (applied and reaction): energy floor ``Σ |F_j| floor_q,j(t)``
    force: np.ndarray
    #: the floor of the ``λ`` components
    floor_lam: np.ndarray
    #: how far each row's explicit time terms move over the run at the initial state: ``max_t |g(q₀, t) − g(q₀, t₀)|``
    #: and the same of ``Φ`` (a prescribed target's excursion; zero for a scleronomic row)
    target_g: np.ndarray
    target_Phi: np.ndarray

    def atol(self, rtol: float, iterates: bool = False) -> np.ndarray:
        """The absolute tolerance of an adaptive run on ``(q, v, λ)``: ``rtol·S``, not below ``ROUNDOFF·M`` — nor, for
        a method that solves its stages by iteration (``iterates``: Radau, BDF, CVODES), below ``rtol·M``: the
        iteration's increments carry the right-hand side's round-off, and a tolerance below it is never met."""
        size = np.concatenate([self.q, self.v, self.lam])
        floor = np.concatenate([self.floor_q, self.floor_v, self.floor_lam])
        least = max(rtol, ROUNDOFF) if iterates else ROUNDOFF
        atol = np.maximum(ATOL_SHARE * rtol * size, least * floor)
        return np.maximum(one_digit(atol), TINY)

    def floors(self, elapsed: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The round-off floors after ``elapsed`` time (one row per sample): of the coordinates (``nq``), of the
        displacements along each velocity component and of the velocities (``nv`` each)."""
        dt = np.abs(np.asarray(elapsed, float))[:, None]
        v = self.floor_v[None, :] + self.accel[None, :] * dt
        disp = self.floor_dq[None, :] + self.floor_v[None, :] * dt + self.accel[None, :] * dt**2
        if self.floor_q.size == self.floor_v.size:
            return disp, disp, v
        grown = self.floor_q[None, :] + np.max(disp - self.floor_dq[None, :], axis=1, initial=0.0)[:, None]
        return grown, disp, v

    def energy_floor(self, elapsed: np.ndarray) -> np.ndarray:
        """``Σ_j |F_j| M_q,j(t)``: the work of the machine's forces over its round-off displacements."""
        _, disp, _ = self.floors(elapsed)
        return disp @ self.force  # type: ignore[no-any-return]


def run_scales(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, horizon: float = 0.0
) -> RunScales:
    """The scales of a run of ``model`` from ``(t, q, v, λ)`` over ``horizon`` (``t_end − t₀``; module docstring)."""
    data = model.evaluate_data(t, q, v, lam)
    A = np.asarray(data.A, float)
    diag = np.abs(np.diag(A)) if A.size else np.zeros(0)
    diag = np.where(np.isfinite(diag) & (diag > 0), diag, np.inf)
    mass = np.where(np.isfinite(diag), diag, 0.0)
    coupling = structure(model)
    acc, u = _motion(model, data)
    reaction = data.D @ u if data.D.size else np.zeros(model.nv)
    force = np.nan_to_num(np.abs(data.f) + np.abs(data.r0) + np.abs(reaction), nan=0.0, posinf=0.0)
    # the machine's floors, part by part: coordinates weighed by the inertia that moves with them, velocities by
    # the work of the forces over them
    q_v = coupling.velocity_sized(np.abs(q))
    kinetic = np.nan_to_num(0.5 * v * (A @ v)) if A.size else np.zeros(model.nv)
    k_q = coupling.part_max(q_v**2 * mass)
    # a part whose coordinates all start at zero: the way its motion, else its forces, take it in the run
    with np.errstate(over="ignore"):  # an absurd horizon gives infinite sizes, not an OverflowError
        span = np.float64(horizon)
        k_q = np.where(k_q > 0, k_q, 2.0 * coupling.part_sum(np.maximum(kinetic, 0.0)) * span**2)
        k_q = np.where(k_q > 0, k_q, coupling.part_max(np.nan_to_num(force**2 / diag)) * span**4)
    targets = _targets(model, t, q, v, lam, data, horizon)
    reach_g, reach_Phi = _target_reach(model, t, q, v, lam, targets)
    k_q = np.where(k_q > 0, k_q, coupling.part_max(reach_g**2 * mass))
    mobility = _mobility(A, np.asarray(data.J, float), diag)
    nearby = _mobility_nearby(model, t, q, lam, data, diag, np.sqrt(k_q.max(initial=0.0)))
    # held at this instant only (moves a little way on): the machine's size unconstrained, 1/A_jj
    mobility = np.where((mobility == 0) & (nearby > 0), np.nan_to_num(1.0 / diag), mobility)
    floor_dq = np.sqrt(k_q / diag)
    reach = np.maximum(q_v, floor_dq)
    energy = coupling.part_sum(force * reach + np.maximum(kinetic, 0.0))
    energy = np.where(energy > 0, energy, coupling.part_max(0.5 * mass * reach_Phi**2))  # a target's speed
    floor_v = np.sqrt(2.0 * energy / diag)
    floor_q = coupling.coordinate_sized(floor_dq)
    accel = force / diag
    # the motion's sizes: what is below round-off of its floor is zero, and a zero size is the machine's, along
    # the motions the constraints allow (the round-off floor where they allow none)
    size = np.maximum(reach, floor_dq)
    typical = np.maximum(accel, np.nan_to_num(energy / (diag * np.where(size > 0, size, np.inf))))
    acc = np.where(np.abs(acc) <= CHECK_ROUNDOFF * typical, 0.0, np.abs(acc))  # the part's work over its size
    free_q = coupling.coordinate_sized(np.sqrt(k_q * mobility))  # zero where the rows hold it: round-off only
    size_q = _sized(np.abs(q), floor_q, free_q)
    free_v = np.nan_to_num(np.sqrt(2.0 * energy * mobility))
    size_v = _sized(np.abs(v) + np.sqrt(acc * coupling.velocity_sized(size_q)), floor_v, free_v)
    declared = model.scales
    if declared is not None:
        size_q, floor_q = _override(size_q, declared.q), _override(floor_q, declared.q)
        size_v, floor_v = _override(size_v, declared.v), _override(floor_v, declared.v)
        if model.nq == model.nv:
            floor_dq = floor_q
    lam_size, lam_floor = _lambda_scales(model, data, lam, diag, floor_v)
    return RunScales(
        q=size_q,
        v=size_v,
        lam=_sized(lam_size, lam_floor, lam_floor),
        floor_q=np.nan_to_num(floor_q),
        floor_dq=np.nan_to_num(floor_dq),
        floor_v=np.nan_to_num(floor_v),
        accel=np.nan_to_num(accel),
        force=force,
        floor_lam=lam_floor,
        target_g=targets[0],
        target_Phi=targets[1],
    )


#: The instants, as fractions of the run, at which a row's explicit time terms are read (a rest-to-rest target can
#: be back where it started at the end).
TARGET_INSTANTS = (0.25, 0.5, 0.75, 1.0)


def _targets(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, data: Any, horizon: float
) -> tuple[np.ndarray, np.ndarray]:
    """``max_t |g(q₀, t) − g(q₀, t₀)|`` and the same of ``Φ`` over :data:`TARGET_INSTANTS` of the run."""
    g0, Phi0 = np.asarray(data.g, float), np.asarray(data.Phi, float)
    moved_g, moved_Phi = np.zeros(model.k), np.zeros(model.k)
    if model.k == 0 or not horizon > 0:
        return moved_g, moved_Phi
    for share in TARGET_INSTANTS:
        later = model.evaluate_data(t + share * horizon, q, v, lam)
        moved_g = np.fmax(moved_g, np.abs(np.asarray(later.g, float) - g0))
        moved_Phi = np.fmax(moved_Phi, np.abs(np.asarray(later.Phi, float) - Phi0))
    return np.nan_to_num(moved_g), np.nan_to_num(moved_Phi)


def _target_reach(
    model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, targets: tuple[np.ndarray, np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """How far and how fast prescribed targets move each velocity component: each row's excursion (``targets``:
    of ``g``, of ``Φ``) shared by the components it depends on (``moved_i / Σ_j |∂g_i/∂q_j|``, with ``J`` for the
    speeds), the largest over the rows."""
    moved_g, moved_Phi = targets
    if model.k == 0 or not (np.any(moved_g > 0) or np.any(moved_Phi > 0)):
        return np.zeros(model.nv), np.zeros(model.nv)
    _, G, J = sensitivities(model, np.array([t]), np.concatenate([q, v, lam])[None, :], 1)

    def shared(moved: np.ndarray, D: np.ndarray) -> np.ndarray:
        per_row = moved / np.where(D.sum(axis=1) > 0, D.sum(axis=1), np.inf)
        return np.max(np.where(D > 0, per_row[:, None], 0.0), axis=0, initial=0.0)

    return structure(model).velocity_sized(shared(moved_g, G[0])), shared(moved_Phi, J[0])


@dataclass(frozen=True)
class Coupling:
    """Which components of a model belong together: the parts of the graph whose edges are the mass matrix's and
    the constraint rows' structural nonzeros (a free coordinate far away is a part of its own, and its size does
    not enter the others' scales), and which coordinates each velocity component moves (``q̇ = K(q) v``)."""

    #: the part of each velocity component
    part: np.ndarray
    #: ``moves[i, j]``: coordinate ``i`` moves with velocity component ``j`` (structurally)
    moves: np.ndarray

    def part_max(self, values: np.ndarray) -> np.ndarray:
        """The largest of ``values`` (one per velocity component) over each component's part."""
        out = np.zeros_like(values)
        for p in np.unique(self.part):
            out[self.part == p] = np.max(values[self.part == p], initial=0.0)
        return out

    def part_sum(self, values: np.ndarray) -> np.ndarray:
        """The sum of ``values`` over each component's part."""
        out = np.zeros_like(values)
        for p in np.unique(self.part):
            out[self.part == p] = np.sum(values[self.part == p])
        return out

    def velocity_sized(self, values_q: np.ndarray) -> np.ndarray:
        """Each velocity component's size from the coordinates it moves (the largest)."""
        return np.max(np.where(self.moves, values_q[:, None], 0.0), axis=0, initial=0.0)

    def coordinate_sized(self, values_v: np.ndarray) -> np.ndarray:
        """Each coordinate's size from the velocity components that move it (the largest)."""
        return np.max(np.where(self.moves, values_v[None, :], 0.0), axis=1, initial=0.0)


def structure(model: Model) -> Coupling:
    """The model's :class:`Coupling`, from the sparsity of its expressions (kept in the workspace)."""

    def build() -> Coupling:
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        mech, p = model.mechanism, model.expressions
        nv = model.nv
        pattern = np.array(ca.DM(ca.SX(mech.A).sparsity(), 1)).astype(bool) if nv else np.zeros((0, 0), bool)
        rows = [ca.SX(p.J)] + ([ca.jacobian(p.g, mech.q) @ ca.jacobian(mech.qdot, mech.v)] if p.g is not None else [])
        for J in rows:
            inc = np.array(ca.DM(J.sparsity(), 1)).astype(bool)
            for row in inc:
                idx = np.flatnonzero(row)
                pattern[np.ix_(idx, idx)] = True
        forces = ca.jacobian(ca.SX(p.f), mech.q) @ ca.jacobian(mech.qdot, mech.v)  # springs join what they join
        pattern |= np.array(ca.DM(forces.sparsity(), 1)).astype(bool)
        graph = coo_matrix(pattern | pattern.T | np.eye(nv, dtype=bool))
        _, part = connected_components(graph, directed=False)
        if model.nq == model.nv:
            moves = np.eye(nv, dtype=bool)
        else:
            moves = np.array(ca.DM(ca.jacobian(mech.qdot, mech.v).sparsity(), 1)).astype(bool)
        return Coupling(part=np.asarray(part), moves=moves)

    return workspace(model).get(("scales: coupled parts",), build)


def _mobility(A: np.ndarray, J: np.ndarray, diag: np.ndarray) -> np.ndarray:
    """The diagonal of the constrained mobility ``A⁻¹ − A⁻¹Jᵀ (J A⁻¹ Jᵀ)⁺ J A⁻¹``: how fast each component moves per
    unit of momentum along the motions the constraints allow (``1/A_jj`` where ``A`` cannot be inverted).

    Computed in the units of the machine itself — ``A`` scaled to a unit diagonal, each row of ``J`` to unit length
    — so that the pseudo-inverse's cut-off, and so the answer, is the same in any units."""
    n = A.shape[0] if A.ndim == 2 else 0
    fallback = np.nan_to_num(1.0 / diag)
    d = np.where(np.isfinite(diag), diag, 0.0)
    if n == 0 or not (np.all(np.isfinite(A)) and np.all(np.isfinite(J))) or not np.all(d > 0):
        return fallback
    root = np.sqrt(d)
    try:
        inverse = np.linalg.inv(A / np.outer(root, root))
    except np.linalg.LinAlgError:
        return fallback
    if J.size:
        J = J / root[None, :]
        norms = np.linalg.norm(J, axis=1)
        J = J[norms > 0] / norms[norms > 0, None]
        if J.size:
            AJ = inverse @ J.T
            inverse = inverse - AJ @ np.linalg.pinv(J @ AJ, hermitian=True) @ AJ.T
    c = np.diag(inverse)
    c = np.where(c > CHECK_ROUNDOFF, c, 0.0)  # a component the rows hold: what is left is round-off
    return np.where(np.isfinite(c), c / d, fallback)


#: How far along the constraints the mobility is read a second time, relative to the machine's size.
NEARBY = 1e-3


def _mobility_nearby(
    model: Model, t: float, q: np.ndarray, lam: np.ndarray, data: Any, diag: np.ndarray, size: float
) -> np.ndarray:
    """The mobility a little way along the motions the constraints allow (a fixed generic direction of their
    tangent space, :data:`NEARBY` of the machine's size ``√K_q`` in the kinetic metric): a coordinate the rows hold
    only at this instant (a pendulum's ``x`` when its arm is level) moves there, one they hold by their structure (a
    hinge's spin about a rod) does not."""
    A, J = np.asarray(data.A, float), np.asarray(data.J, float)
    nv = model.nv
    if not (size > 0 and np.isfinite(size)) or not (np.all(np.isfinite(A)) and np.all(np.isfinite(J))):
        return np.zeros(nv)
    basis = _null_space(J, nv)
    if basis.shape[1] == 0:
        return np.zeros(nv)
    weights = np.random.default_rng(1989).standard_normal(basis.shape[1])  # any fixed generic direction
    tangent = basis @ weights
    norm = float(np.sqrt(max(tangent @ A @ tangent, 0.0)))
    if not norm > 0:
        return np.zeros(nv)
    rate = model.evaluate_data(t, q, tangent / norm, lam).qdot
    q1 = model.mechanism.normalize_array(q + NEARBY * size * np.asarray(rate, float))
    there = model.evaluate_data(t, q1, np.zeros(nv), lam)
    return _mobility(np.asarray(there.A, float), np.asarray(there.J, float), diag)


def _null_space(J: np.ndarray, n: int) -> np.ndarray:
    """An orthonormal basis of the null space of ``J`` (rows scaled to unit length first, so in any units)."""
    if not J.size:
        return np.eye(n)
    norms = np.linalg.norm(J, axis=1)
    J = J[norms > 0] / norms[norms > 0, None]
    if not J.size:
        return np.eye(n)
    _, sv, vt = np.linalg.svd(J)
    rank = int(np.sum(sv > sv[0] * max(J.shape) * EPS)) if sv.size else 0
    return vt[rank:].T


def _sized(size: np.ndarray, floor: np.ndarray, free: np.ndarray) -> np.ndarray:
    """``size``, with the machine's size ``free`` where it is zero to round-off of ``floor`` (no information about
    the motion)."""
    return np.where(np.abs(size) <= CHECK_ROUNDOFF * np.nan_to_num(floor), np.nan_to_num(free), size)


def _motion(model: Model, data: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(q̈, u)`` at the state: the least-squares solution of ``A q̈ − D u = f + r₀``, ``J q̈ = φ`` (numpy alone:
    defined for redundant rows and at a state the step refuses; only magnitudes are read)."""
    A, D, J = np.asarray(data.A, float), np.asarray(data.D, float), np.asarray(data.J, float)
    n, m, k = A.shape[0], D.shape[1] if D.ndim == 2 else 0, J.shape[0] if J.ndim == 2 else 0
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(data.f))):
        return np.zeros(n), np.zeros(m)
    if k == 0 or m == 0:
        try:
            return np.linalg.solve(A, data.f + data.r0), np.zeros(m)
        except np.linalg.LinAlgError:
            return np.zeros(n), np.zeros(m)
    kkt = np.block([[A, -D], [J, np.zeros((k, m))]])
    rhs = np.concatenate([data.f + data.r0, data.phi])
    if not (np.all(np.isfinite(kkt)) and np.all(np.isfinite(rhs))):
        return np.zeros(n), np.zeros(m)
    x = np.linalg.lstsq(kkt, rhs, rcond=None)[0]
    return x[:n], x[n:]


def _override(derived: np.ndarray, declared: Sequence[float | None] | None) -> np.ndarray:
    if declared is None:
        return derived
    return np.array([d if x is None else x for d, x in zip(derived, declared, strict=True)], float)


def _lambda_scales(
    model: Model, data: Any, lam: np.ndarray, diag: np.ndarray, floor_v: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``|λ₀|`` and the floor of each ``λ`` state: ``Dλ`` is an impulse, so ``λ_i ~ Σ_j |D_ji| A_jj M_v,j / Σ_j D_ji²``
    (the machine's momentum along the reaction's direction)."""
    if not model.n_lam:
        return np.zeros(0), np.zeros(0)
    D = np.asarray(data.D, float)[:, model.lam_columns]
    weight = np.where(np.isfinite(diag), diag, 0.0) * floor_v
    norm2 = (D**2).sum(axis=0)
    floor = np.where(norm2 > 0, np.abs(D).T @ weight / np.where(norm2 > 0, norm2, 1.0), 0.0)
    return np.abs(lam), np.nan_to_num(floor)


def row_scales(
    model: Model, scales: RunScales, t: np.ndarray, y: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each bilateral row's scale at each of the first ``n`` samples of ``(t, y)`` and its round-off floor:
    ``(s_g, s_Φ, floor_g, floor_Φ)``, each ``(n, k)``.

    ``s_g,i = Σ_j |∂g_i/∂q_j| · max(|q_j|, S_q,j)``, each factor the largest reached so far (and at least that of
    the run's first tenth: a departure is judged against the motion before it, never against the state it ran off
    to), ``s_Φ`` the same with ``J`` and the velocities; ``floor_g,i = CHECK_ROUNDOFF·Σ_j |∂g_i/∂q_j| M_q,j(t)``,
    ``floor_Φ`` the same. A residual is within ``tol`` where ``|r| ≤ max(tol·s, floor)`` (:func:`within`)."""
    nq, nv, k = model.nq, model.nv, model.k
    if n == 0 or k == 0:
        empty = np.zeros((n, k))
        return empty, empty, empty, empty
    idx, G, J = sensitivities(model, t, y, n)
    early = max(1, n // 10)
    q_size = np.maximum(_reached_rows(np.abs(y[:n, :nq]), early), scales.q[None, :])
    v_size = np.maximum(_reached_rows(np.abs(y[:n, nq : nq + nv]), early), scales.v[None, :])
    G = np.maximum.accumulate(G, axis=0)
    J = np.maximum.accumulate(J, axis=0)
    early_at = int(np.searchsorted(idx, early, side="right")) - 1
    G = np.maximum(G, G[max(early_at, 0)][None])
    J = np.maximum(J, J[max(early_at, 0)][None])
    at = np.searchsorted(idx, np.arange(n), side="right") - 1  # the sensitivities read at or before each sample
    s_g, s_Phi = np.empty((n, k)), np.empty((n, k))
    floor_q, _, floor_v = scales.floors(t[:n] - t[0])
    f_g, f_Phi = np.empty((n, k)), np.empty((n, k))
    for s in np.unique(at):
        rows = at == s
        s_g[rows], s_Phi[rows] = q_size[rows] @ G[s].T, v_size[rows] @ J[s].T
        f_g[rows], f_Phi[rows] = floor_q[rows] @ G[s].T, floor_v[rows] @ J[s].T
    s_g = np.maximum(s_g, scales.target_g[None, :])  # at least a prescribed target's own excursion
    s_Phi = np.maximum(s_Phi, scales.target_Phi[None, :])
    return s_g, s_Phi, CHECK_ROUNDOFF * f_g, CHECK_ROUNDOFF * f_Phi


def _reached_rows(values: np.ndarray, early: int) -> np.ndarray:
    """The largest of each column up to each row (NaN skipped), and at least up to row ``early``."""
    running = np.fmax.accumulate(np.where(np.isnan(values), -np.inf, values), axis=0)
    running = np.maximum(running, running[min(early, values.shape[0] - 1)][None, :])
    return np.where(np.isfinite(running), running, np.where(running > 0, np.inf, 0.0))


def within(residual: np.ndarray, scale: np.ndarray, floor: np.ndarray, tol: float) -> np.ndarray:
    """``|r| / (tol·s)``, with a residual within its round-off floor counted as 0 (NaN stays NaN): ``≤ 1`` keeps."""
    r = np.abs(residual)
    limit = tol * scale
    ratio = r / np.where(limit > 0, limit, np.inf)
    ratio = np.where(limit > 0, ratio, np.where(r > 0, np.inf, 0.0))
    return np.where(r <= floor, 0.0, ratio)


def sensitivities(model: Model, t: np.ndarray, y: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The samples read (``idx``, up to :data:`SENSITIVITY_SAMPLES` of the first ``n``, spread over them) and there
    ``|∂g/∂q|`` (``(len(idx), k, nq)``, zero on rows without a position residual) and ``|J|`` (``(len(idx), k, nv)``):
    one call of a mapped function, kept in the workspace. A sample that is not finite reads the one before."""
    nq, nv, k = model.nq, model.nv, model.k
    idx = np.unique(np.linspace(0, n - 1, min(n, SENSITIVITY_SAMPLES)).astype(int))
    states = np.zeros((1 + nq + nv + model.n_lam, SENSITIVITY_SAMPLES))
    states[0, : idx.size] = t[idx]
    states[1:, : idx.size] = y[idx, : nq + nv + model.n_lam].T
    good = np.isfinite(states[:, : idx.size]).all(axis=0)
    for i in range(idx.size):
        if not good[i]:
            states[:, i] = states[:, i - 1] if i else 0.0
    states[:, idx.size :] = states[:, :1]
    G, J = _sensitivity_function(model)(states)
    G = np.nan_to_num(np.array(G).reshape(k, nq, SENSITIVITY_SAMPLES, order="F"))[:, :, : idx.size]
    J = np.nan_to_num(np.array(J).reshape(k, nv, SENSITIVITY_SAMPLES, order="F"))[:, :, : idx.size]
    return idx, np.moveaxis(G, 2, 0), np.moveaxis(J, 2, 0)


def _sensitivity_function(model: Model) -> ca.Function:
    def build() -> ca.Function:
        mech, p = model.mechanism, model.expressions
        state = ca.vertcat(mech.t, mech.q, mech.v, model.lam)
        k = model.k
        g = p.g if p.g is not None else ca.SX.zeros(k)
        G = ca.fabs(ca.jacobian(g, mech.q))
        J = ca.fabs(p.J)
        one = ca.Function("row_sensitivities", [state], [ca.vec(G), ca.vec(J)])
        return one.map(SENSITIVITY_SAMPLES)

    return workspace(model).get(("row sensitivities, mapped",), build)


def energy_scale(
    model: Model,
    scales: RunScales,
    t: np.ndarray,
    energy: np.ndarray,
    kinetic: np.ndarray,
    works: tuple[np.ndarray, np.ndarray],
    early: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The energy balance's scale at each sample and its round-off floor (module docstring): ``(scale, floor)``.

    ``scale``: the largest kinetic energy, the potential's range ``max V − min V`` (``V = E − T``), the exchanges
    ``|E − E₀|`` and the works ``|W_R|, |W_F|`` reached so far (at least those of sample ``early``, if given; the
    whole run if ``early`` is None). ``floor``: ``CHECK_ROUNDOFF·(max|E|, max T, max|V| + Σ_j |F_j| M_q,j(t))``."""
    E = np.nan_to_num(energy, nan=0.0, posinf=0.0, neginf=0.0)
    T = np.nan_to_num(kinetic, nan=0.0, posinf=0.0, neginf=0.0)
    V = E - T
    W_R, W_F = (np.nan_to_num(w - w[0], nan=0.0) for w in works)
    exchange = np.abs(E - E[0]) + np.abs(W_R) + np.abs(W_F)
    spread = _reached(np.maximum(V, V[0]) if V.size else V) - _least(V)
    size = _reached(T) + spread + _reached(exchange)
    floor = CHECK_ROUNDOFF * (_reached(np.abs(E)) + _reached(T) + _reached(np.abs(V)))
    floor = floor + CHECK_ROUNDOFF * scales.energy_floor(t - t[0])
    if early is None:
        return np.full_like(size, size[-1] if size.size else 0.0), np.full_like(floor, floor[-1] if floor.size else 0)
    early = min(early, size.size - 1)
    return np.maximum(size, size[early]), np.maximum(floor, floor[early])


def _reached(values: np.ndarray) -> np.ndarray:
    return np.maximum.accumulate(values) if values.size else values


def _least(values: np.ndarray) -> np.ndarray:
    return np.minimum.accumulate(values) if values.size else values


def one_digit(values: np.ndarray) -> np.ndarray:
    """Each value rounded to one significant decimal digit (1, 2, …, 9 times a power of ten): a scale is an order
    of magnitude, two models of one machine whose numbers differ in their last bits take the same steps, and a change
    to decimal units (millimetres, tonnes) moves the grid onto itself."""
    values = np.asarray(values, float)
    positive = values > 0
    decade = np.power(10.0, np.floor(np.log10(np.where(positive, values, 1.0))))
    return np.where(positive, np.round(values / decade) * decade, values)


def scales_at_first(model: Model, t: np.ndarray, y: np.ndarray) -> RunScales:
    """The run's scales read at its first sample (for a caller that did not keep the run's own)."""
    nq, nv, nl = model.nq, model.nv, model.n_lam
    horizon = float(t[-1] - t[0]) if t.size else 0.0
    return run_scales(model, float(t[0]), y[0, :nq], y[0, nq : nq + nv], y[0, nq + nv : nq + nv + nl], horizon)
