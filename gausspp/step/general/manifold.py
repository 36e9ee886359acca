"""Where the state stands relative to the constraint manifold, and the nearest state on it.

Redundancy is decided on the manifold (docs/theory.md §7): rows that are dependent there but
independent at a drifted state would amplify the drift by one over their tiny angle. The
general step therefore looks at the nearest state on the constraints (:func:`nearest_on_manifold`)
and builds the reference problem there (:func:`reference_problem`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ...errors import RealizabilityError
from ...workspace import workspace
from .. import dense
from ..bound import Bound, dense_outputs, load_inputs
from ..data import evaluate
from ..protocol import StepModel
from .model_qp import gauss_problem
from .redundancy import CLEARLY_INDEPENDENT, independent_rows
from .solve import GaussProblem

#: Nearest state on the manifold: a row residual (as a coordinate distance) above this fraction of the state's
#: size means that the dependent rows cannot hold together — they contradict each other.
REACH_TOL = 1e-8


def off_manifold(
    model: StepModel, J: np.ndarray, Phi: np.ndarray, g: np.ndarray, q: np.ndarray, v: np.ndarray
) -> tuple[float, int]:
    """How far the state is from the constraints, and the row farthest off.

    Each row's residual is a distance in coordinates (``|g_i| / ‖J_i‖``, ``|Φ_i| / ‖J_i‖``) relative to the size
    of the components the row depends on (:func:`_row_size`); compared with :data:`REACH_TOL`.
    """
    norms = np.sqrt(np.einsum("ij,ij->i", J, J))
    norms[norms == 0] = 1.0
    rows = model.holonomic_rows
    off = np.abs(Phi) / norms / (1.0 + _row_size(J, v))
    q_size = _row_size(J, q) if q.size == v.size else np.full(J.shape[0], float(np.abs(q).max(initial=0.0)))
    off[rows] = np.maximum(off[rows], np.abs(g[rows]) / norms[rows] / (1.0 + q_size[rows]))
    worst = int(np.argmax(off)) if off.size else 0
    return (float(off[worst]) if off.size else 0.0), worst


def _row_size(J: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The size of the components each row depends on, ``Σ_j |J_ij||x_j| / Σ_j |J_ij|`` — not the largest component
    of the whole state (a far coordinate the row does not involve does not loosen it)."""
    weight = np.abs(J).sum(axis=1)
    return np.abs(J) @ np.abs(x) / np.where(weight > 0, weight, 1.0)


def on_manifold(model: StepModel, J: np.ndarray, Phi: np.ndarray, g: np.ndarray, q: np.ndarray, v: np.ndarray) -> bool:
    """True if the state is on the constraints to :data:`REACH_TOL` (always, without bilateral rows)."""
    return model.k == 0 or off_manifold(model, J, Phi, g, q, v)[0] <= REACH_TOL


def check_reachable(
    model: StepModel, t: float, J: np.ndarray, Phi: np.ndarray, g: np.ndarray, q: np.ndarray, v: np.ndarray
) -> None:
    """Raise if the nearest state found is not on the constraints: then they contradict each other."""
    size, worst = off_manifold(model, J, Phi, g, q, v)
    if size <= REACH_TOL:
        return
    raise RealizabilityError(
        f"the constraint rows of {', '.join(map(repr, model.names))} are dependent and contradict each other at "
        f"t={t:.6g}: no state near this one "
        f"satisfies them all (row {model.row_names[worst]!r} stays off by {size:.2g} relative to the state's size) "
        "— the redundant rows describe different constraints; remove one of them",
        t=t,
        constraint=model.row_names[worst],
        margin=0.0,
    )


Kinematics = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


def _build_kinematics(model: StepModel) -> Kinematics:
    mech = model.mechanism
    K = ca.jacobian(mech.qdot, mech.v)
    if K.is_constant():  # generalized coordinates (q̇ = v): one matrix for every state
        value = np.array(ca.evalf(K), dtype=float)
        return lambda t, q, v: value
    bound = Bound(ca.Function("K", [mech.t, mech.q, mech.v], dense_outputs([K])))

    def call(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        load_inputs(bound.args, (t, q, v))
        bound.eval()
        return bound.res[0].reshape(bound.shapes[0], order="F").copy()

    return call


def _kinematics(model: StepModel) -> Kinematics:
    """``∂q̇/∂v`` at ``(t, q, v)``: how a change of velocity coordinates moves ``q`` (the identity unless
    ``q̇ ≠ v``)."""
    return workspace(model).get(("kinematics",), lambda: _build_kinematics(model))


def _correction(A: np.ndarray, J: np.ndarray, D: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """The least-squares move along ``A⁻¹D`` that removes ``residual`` of the rows ``J`` to first order (each row
    scaled to unit length first: rows of different units — a point's, an axis's — weigh the same, and the rank
    cut-off means the same in any units)."""
    AinvD = dense.solve(A, D)
    M = J @ AinvD
    norms = np.sqrt(np.einsum("ij,ij->i", M, M))
    norms = np.where(norms > 0, norms, 1.0)
    return AinvD @ dense.lstsq(M / norms[:, None], residual / norms, 1e-10)


def _project_positions(
    model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, phase: str, iterations: int
) -> np.ndarray:
    """Gauss–Newton onto the holonomic rows ``g(q, t) = 0``: the clearly independent ones, or all of them."""
    rows = model.holonomic_rows
    cols = [c for grp in model.groups if grp.rows.start in rows for c in range(grp.cols.start, grp.cols.stop)]
    previous = np.inf
    for _ in range(iterations):
        d = evaluate(model, t, q, v, lam)
        J, g, D = d.J[rows], d.g[rows], d.D[:, cols]
        use = np.arange(len(rows))
        if phase == "clear":
            use, _ = independent_rows(dense.solve(dense.cholesky(d.A), J.T).T, CLEARLY_INDEPENDENT)
        size = float(np.max(np.abs(g[use]), initial=0.0))
        if not size < previous or size == 0.0:  # converged to round-off (or no longer converging)
            break
        previous = size
        step = _correction(d.A, J[use], D, g[use])
        q = model.mechanism.normalize_array(q - _kinematics(model)(t, q, v) @ step)
    return q


def nearest_on_manifold(
    model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, iterations: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """The state on the constraints nearest ``(q, v)``, moving along the realizations' directions ``A⁻¹D``.

    Gauss–Newton onto ``g(q, t) = 0`` (holonomic rows) in two phases: first with the rows that are clearly
    independent here (:data:`~gausspp.step.redundancy.CLEARLY_INDEPENDENT`, in the order declared: a square
    step on rows that are dependent on the manifold would be huge along their near-null direction), then
    with every row in least squares; then ``v`` onto ``Φ = 0`` (affine in ``v``: one least-squares step).
    Works with redundant rows, where the compiled projection (:func:`gausspp.simulation.drift.projection_function`)
    cannot.
    """
    q_ref = q.copy()
    for phase in ("clear", "all") if model.holonomic_rows else ():
        q_ref = _project_positions(model, t, q_ref, v, lam, phase, iterations)
    d = evaluate(model, t, q_ref, v, lam)
    v_ref = v - _correction(d.A, d.J, d.D, d.Phi) if np.any(d.Phi) else v
    return q_ref, v_ref


def reference_problem(
    model: StepModel, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, stab: Any, closed: np.ndarray
) -> GaussProblem | None:
    """The step problem at the nearest state on the constraint manifold, where redundancy is decided.

    ``None`` when the state is on the manifold already (decide there). Raises if even the nearest state
    found is off the constraints (:func:`check_reachable`).
    """
    q_ref, v_ref = nearest_on_manifold(model, t, q, v, lam)
    d = evaluate(model, t, q_ref, v_ref, lam, stab)
    check_reachable(model, t, d.J, d.Phi, d.g, q_ref, v_ref)
    if np.array_equal(q_ref, q) and np.array_equal(v_ref, v):
        return None
    if not (np.all(np.isfinite(d.A)) and np.all(np.isfinite(d.f + d.r0))):
        return None
    try:
        a0 = np.linalg.solve(d.A, d.f + d.r0)
    except np.linalg.LinAlgError:
        return None
    return gauss_problem(model, t, d.A, a0, d.J, d.phi, d.D, d.Jc, d.phic[closed], closed)
