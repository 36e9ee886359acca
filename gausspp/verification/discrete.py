"""The discretized inequality (23) and its two solvers (paper §6; see :mod:`gausspp.verification.integral`).

On the nodes ``t₀ < … < t_N`` of a path, :class:`Discretized` holds ``R = A ẍ − f``, the metric ``G`` and the
relation (20) ``E1 η̇ + E0 η = 0`` per constraint row. :func:`solve_qp` minimizes the left side of (23) over
admissible ``η`` (``η = 0`` at both ends, trapezoid rule for the integral, pointwise rows at interior nodes,
differential rows by the midpoint rule on each interval) as one sparse convex QP through casadi's ``conic``
interface; :func:`solve_closed_form` does the same node by node for pointwise relations, a second path that
cross-checks the QP. Both return ``(minimum − value_at_zero, η, λ)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from ..errors import InputError, QPSolveError
from ..step.general import RANK_TOL


@dataclass(frozen=True)
class Discretized:
    """(23) on nodes: ``R``, metric ``G`` and the relation (20) per constraint row.

    ``E1``/``E0`` are ``(N+1, k, n)``; rows with ``pointwise[r]`` true have ``E1 = 0`` and hold
    at each interior node, the others on each interval by the midpoint rule. ``f`` (optional)
    is the known force ``F − h`` (plus any known reaction) and ``momentum`` (optional) is ``A v``:
    the sizes ``R`` is measured against (see :func:`normalizer`).
    """

    t: np.ndarray
    R: np.ndarray
    G: np.ndarray
    E1: np.ndarray
    E0: np.ndarray
    pointwise: np.ndarray
    f: np.ndarray | None = None
    momentum: np.ndarray | None = None

    def every_other(self) -> Discretized:
        idx = np.arange(0, self.t.size, 2)
        if idx[-1] != self.t.size - 1:
            idx = np.append(idx, self.t.size - 1)
        f = None if self.f is None else self.f[idx]
        p = None if self.momentum is None else self.momentum[idx]
        return Discretized(self.t[idx], self.R[idx], self.G[idx], self.E1[idx], self.E0[idx], self.pointwise, f, p)


# -- the discrete problem ---------------------------------------------------------------------
def _weights(t: np.ndarray) -> np.ndarray:
    h = np.diff(t)
    w = np.zeros(t.size)
    w[:-1] += h / 2
    w[1:] += h / 2
    return w


def _mean_square(t: np.ndarray, G: np.ndarray, X: np.ndarray) -> float:
    """``(1/T) ∫ (G⁻¹X, X) dt`` by the trapezoid rule."""
    quad = np.einsum("ni,ni->n", X, np.linalg.solve(G, X[..., None])[..., 0])
    return float(_weights(t) @ quad / (t[-1] - t[0]))


def value_at_zero(d: Discretized) -> float:
    """``(1/T) ∫ (G⁻¹R, R) dt`` by the trapezoid rule."""
    return _mean_square(d.t, d.G, d.R)


#: A reaction whose mean square is below this share of :func:`balance` is round-off: no reaction at all.
NEGLIGIBLE = 1e-8


def forces(d: Discretized) -> float:
    """The size of the terms ``R = A ẍ − f`` balances, ``(1/T) ∫ (G⁻¹Aẍ, Aẍ) + (G⁻¹f, f) dt`` (0 when ``f`` is
    unknown)."""
    if d.f is None:
        return 0.0
    return _mean_square(d.t, d.G, d.R + d.f) + _mean_square(d.t, d.G, d.f)


def balance(d: Discretized) -> float:
    """:func:`forces` plus ``(1/T) ∫ (G⁻¹p, p) dt / T²``: the momentum ``p = A v`` over the horizon ``T`` is the
    force scale of a motion without forces."""
    size = forces(d)
    if d.f is not None and d.momentum is not None:
        size += _mean_square(d.t, d.G, d.momentum) / (d.t[-1] - d.t[0]) ** 2
    return size


def normalizer(d: Discretized) -> float:
    """What the gap is measured against: ``value_at_zero``, or for a path with no relation rows the forces' size;
    never less than :data:`NEGLIGIBLE` times :func:`balance`.

    With relation rows the relative gap is the share of ``(G⁻¹R, R)`` that does work on admissible
    variations. Without any (a free piece: a body in flight between contacts, a saturated servo
    whose force is known) every variation is admissible, the gap is all of ``value_at_zero`` and
    the relative gap would be 1 for any path; there ``R = A ẍ − f`` must vanish, and the gap is
    measured against :func:`forces`, the size of the terms it balances. A path whose reaction is
    round-off (a free motion checked against any realization: ``R ≈ 1e-29``) would otherwise get a
    relative gap of round-off over round-off, of order one; measured against :data:`NEGLIGIBLE` times the
    balance, it is the motion it is.
    """
    floor = NEGLIGIBLE * balance(d)
    if d.E0.shape[1] or d.f is None:
        return max(value_at_zero(d), floor)
    return max(forces(d), floor)


def solve_qp(d: Discretized) -> tuple[float, np.ndarray, np.ndarray]:
    """Minimize the left side of (23) over admissible ``η``: ``(minimum − value_at_zero, η, λ)``.

    The unknowns are ``η`` at the ``m = N − 1`` interior nodes; the objective
    ``Σ wᵢ ((Rᵢ, ηᵢ) + ½(Gᵢηᵢ, ηᵢ))`` (trapezoid weights ``w``), the equalities the rows of
    :func:`pointwise_blocks` then :func:`interval_blocks`.
    """
    N1, n = d.t.size, d.R.shape[1]
    m = N1 - 2  # interior nodes
    w = _weights(d.t)
    H = sp.block_diag([w[i] * d.G[i] for i in range(1, N1 - 1)], format="csc")
    g = np.concatenate([w[i] * d.R[i] for i in range(1, N1 - 1)])
    point_blocks, back = pointwise_blocks(d)
    diff_blocks, row_tags = interval_blocks(d)
    blocks = point_blocks + diff_blocks
    B = sp.vstack(blocks, format="csc") if blocks else sp.csc_matrix((0, m * n))
    x, y = _conic(H, g, B)
    eta = np.zeros((N1, n))
    eta[1:-1] = x.reshape(m, n)
    value = float(g @ x + 0.5 * x @ (H @ x))  # Σ w (Rη + ½ηGη)
    lam = multipliers(d, y, back, row_tags)
    return 2.0 * value / (d.t[-1] - d.t[0]), eta, lam


def pointwise_blocks(d: Discretized) -> tuple[list[sp.spmatrix], list[tuple[int, np.ndarray]]]:
    """The pointwise rows ``E0ᵢ ηᵢ = 0`` at each interior node ``i`` (independent rows only).

    Returns the equality blocks over the interior unknowns and, per node, ``(i, P)`` with ``μ = P y``
    the node's multipliers from those of its independent rows (:func:`_independent_rows`).
    """
    N1, n = d.t.size, d.R.shape[1]
    m = N1 - 2
    blocks: list[sp.spmatrix] = []
    back: list[tuple[int, np.ndarray]] = []  # per node with pointwise rows: (i, P) with μ = P y
    point = np.flatnonzero(d.pointwise)
    if point.size:
        for i in range(1, N1 - 1):
            rows, P = _independent_rows(d.E0[i][point])
            B = sp.lil_matrix((rows.shape[0], m * n))
            B[:, (i - 1) * n : i * n] = rows
            blocks.append(B)
            back.append((i, P))
    return blocks, back


def interval_blocks(d: Discretized) -> tuple[list[sp.spmatrix], list[tuple[str, int, int]]]:
    """The differential rows by the midpoint rule on each interval ``[t_j, t_j+1]``.

    ``Ē1 (η_j+1 − η_j)/h_j + Ē0 (η_j + η_j+1)/2 = 0`` with ``Ē`` the mean of the ends (``η = 0`` at
    the path's ends drops those columns). Returns the blocks and ``("interval", j, r)`` per row.
    """
    N1, n = d.t.size, d.R.shape[1]
    m = N1 - 2
    h = np.diff(d.t)
    blocks: list[sp.spmatrix] = []
    row_tags: list[tuple[str, int, int]] = []  # ("interval", j, r) per differential constraint row
    diff = np.flatnonzero(~d.pointwise)
    if diff.size:
        for j in range(N1 - 1):
            E1 = 0.5 * (d.E1[j][diff] + d.E1[j + 1][diff])
            E0 = 0.5 * (d.E0[j][diff] + d.E0[j + 1][diff])
            B = sp.lil_matrix((diff.size, m * n))
            if j >= 1:
                B[:, (j - 1) * n : j * n] = -E1 / h[j] + E0 / 2
            if j + 1 <= N1 - 2:
                B[:, j * n : (j + 1) * n] = E1 / h[j] + E0 / 2
            blocks.append(B)
            row_tags += [("interval", j, int(r)) for r in diff]
    return blocks, row_tags


def multipliers(
    d: Discretized, y: np.ndarray, back: list[tuple[int, np.ndarray]], row_tags: list[tuple[str, int, int]]
) -> np.ndarray:
    """``λ`` at the nodes from the QP's multipliers ``y``: ``λ = −μ/w`` at nodes, ``λ = −ν/h`` at midpoints.

    Midpoint values reach the nodes by averaging inside and linear extrapolation at the ends; NaN
    where undefined (the ends of pointwise rows).
    """
    N1, k = d.t.size, d.E0.shape[1]
    w, h = _weights(d.t), np.diff(d.t)
    point = np.flatnonzero(d.pointwise)
    diff = np.flatnonzero(~d.pointwise)
    lam = np.full((N1, k), np.nan)
    mids = np.full((N1 - 1, k), np.nan)
    at = 0
    for i, P in back:
        lam[i, point] = -(P @ y[at : at + P.shape[1]]) / w[i]
        at += P.shape[1]
    for (_tag, j, r), yj in zip(row_tags, y[at:], strict=True):
        mids[j, r] = -yj / h[j]
    if diff.size:  # midpoints → nodes: average inside, extrapolate at the ends
        lam[1:-1, diff] = 0.5 * (mids[:-1, diff] + mids[1:, diff])
        lam[0, diff] = 1.5 * mids[0, diff] - 0.5 * mids[1, diff]
        lam[-1, diff] = 1.5 * mids[-1, diff] - 0.5 * mids[-2, diff]
    return lam


def _independent_rows(E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal rows ``Vᵣᵀ`` spanning the rows of ``E = U S Vᵀ`` and the map ``P = Uᵣ Sᵣ⁻¹`` back.

    Dependent rows (redundant constraints: the rows of ``J`` of a closed loop given twice) make
    the QP's equality matrix rank-deficient, and the sparse QR then returns no solution at all
    (``η = 0``: a vacuous verdict). ``Vᵣᵀ η = 0`` has the same solutions as ``E η = 0``; a
    multiplier ``y`` of the former is ``μ = P y`` of the latter, the one of least norm.
    """
    if E.shape[0] == 0:
        return E, np.zeros((0, 0))
    U, S, Vt = np.linalg.svd(E, full_matrices=False)
    r = int(np.sum(S > RANK_TOL * max(S[0], np.finfo(float).tiny)))
    return Vt[:r], U[:, :r] / S[:r]


def _conic(H: sp.spmatrix, g: np.ndarray, B: sp.spmatrix) -> tuple[np.ndarray, np.ndarray]:
    """The equality-constrained convex QP through casadi's conic interface (sparse QR, qrqp)."""
    Hd, Bd = ca.DM(H), ca.DM(B)
    solver = ca.conic(
        "integral_qp",
        "qrqp",
        {"h": Hd.sparsity(), "a": Bd.sparsity()},
        {"print_iter": False, "print_header": False, "print_info": False, "error_on_fail": False},
    )
    zero = np.zeros(B.shape[0])
    sol = solver(h=Hd, g=g, a=Bd, lba=zero, uba=zero)
    x, y = np.array(sol["x"]).ravel(), np.array(sol["lam_a"]).ravel()
    residual = float(np.abs(B @ x).max(initial=0.0)) if np.all(np.isfinite(x)) else float("nan")
    if not residual <= 1e-8 * (1 + np.abs(x).max(initial=0.0)):
        raise QPSolveError(
            f"the discretized (23) was not solved accurately: the relation (20) is violated by {residual:.3g} "
            f"(qrqp status {solver.stats().get('return_status')!r}); the nodes may be too coarse or nearly repeated"
        )
    return x, y


def solve_closed_form(d: Discretized) -> tuple[float, np.ndarray, np.ndarray]:
    """Pointwise relations only: at each interior node minimize over ``ker E0``: ``η = −G⁻¹(R − E0ᵀμ)``."""
    if not d.pointwise.all():
        raise InputError("the closed form needs pointwise relations (N = 0); use method='qp'")
    N1, n = d.R.shape
    w = _weights(d.t)
    eta = np.zeros((N1, n))
    lam = np.full((N1, d.E0.shape[1]), np.nan)
    total = 0.0
    for i in range(1, N1 - 1):
        G, R, E = d.G[i], d.R[i], d.E0[i]
        GiE = np.linalg.solve(G, E.T)
        mu = np.linalg.lstsq(E @ GiE, E @ np.linalg.solve(G, R), rcond=None)[0]
        perp = R - E.T @ mu
        eta[i] = -np.linalg.solve(G, perp)
        lam[i] = mu
        total -= w[i] * perp @ np.linalg.solve(G, perp)
    return total / (d.t[-1] - d.t[0]), eta, lam
