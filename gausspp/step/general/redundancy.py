"""Redundant constraint rows: which to keep, decided on the constraint manifold.

Two kinds of dependent rows reach the step:

* rows dependent **everywhere** (a duplicate, a fixed combination of other rows);
* rows dependent **on the constraint manifold only** — e.g. a four-bar's rocker length, implied
  by the loop closure where the loop is closed. Off the manifold (round-off, integration
  drift, the stages of a Runge–Kutta step) such rows are independent, with a smallest singular
  value of the order of the drift, and their right-hand sides disagree by the drift. Solving
  them exactly then amplifies the drift by ``1/σ_min``: an acceleration that is not the motion.

The rule here: dependence is decided at a *reference* state on the manifold (the state itself
when it is on the manifold, else its projection, :meth:`gausspp.Model.general_step` computes it),
where the kept rows must also be consistent; the step is then solved at the actual state with
the kept rows only. Rows are kept greedily **in the order the constraints were declared**: a row
is dropped when, at the reference, it lies within :data:`DEPENDENCE_TOL` (sine of the angle, in
the kinetic metric ``A⁻¹``) of the span of the rows kept before it — unless the rows so kept turn
nearly dependent while the rank of all rows holds, where a pivoted choice of as many rows is kept
(:func:`chosen_rows`). The answer is then exactly the motion of the minimal model made of the kept
rows — at any drift, not only to within it.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

#: A row whose normalized residual against the rows kept before it (sine of the angle between the row
#: and their span, in the metric A⁻¹) is below this, at the reference state, is dependent on them.
DEPENDENCE_TOL = 1e-7
#: Rows whose smallest sine at the actual state exceeds this are independent whatever the drift: no
#: reference state is needed (drift of 1e-3 moves a sine by about that much).
CLEARLY_INDEPENDENT = 1e-2
#: … and only where the rows' rank holds: their ``r``-th singular value (rows of unit length) at least this. Measured
#: where the kept rows' sine falls below 1e-2: the flyball governor's loops, turning, keep 0.11; the spatial double
#: parallelogram nearing a collinear position is down to 0.035 (a choice made there of rows that look better
#: conditioned still meets the rank drop, and the drift it amplifies reads as a contradiction).
RANK_HOLDS = 5e-2
#: Rows kept in declared order are exchanged for a pivoted choice (:func:`chosen_rows`) when their smallest sine
#: is below :data:`CLEARLY_INDEPENDENT` and the pivoted choice's, as many rows, is this many times larger and
#: clearly independent itself.
SWAP_GAIN = 4.0


def independent_rows(rows: np.ndarray, tol: float = DEPENDENCE_TOL) -> tuple[np.ndarray, np.ndarray]:
    """Greedy selection, in order, of rows that are independent of the rows kept before them.

    Parameters
    ----------
    rows : (k, n) array
        Constraint rows, each of unit length in the metric in which angles are judged.
    tol : float
        A row is dropped when its distance to the span of the kept rows is below ``tol``.

    Returns
    -------
    kept : (r,) int array
        Indices of the kept rows (increasing).
    sines : (k,) array
        Each row's distance to the span of the rows kept before it (its sine against them).
    """
    rows = np.asarray(rows, dtype=float)
    k, n = rows.shape
    basis = np.zeros((min(k, n), n))  # orthonormal rows spanning the kept rows
    kept: list[int] = []
    sines = np.zeros(k)
    for i in range(k):
        r = rows[i]
        size = math.sqrt(float(r @ r))
        if size == 0:
            continue
        r = r / size
        if kept:  # (nothing to project out before the first row is kept)
            B = basis[: len(kept)]
            for _ in range(2):  # Gram–Schmidt twice: orthogonal to round-off even for nearly dependent rows
                r = r - B.T @ (B @ r)
        sines[i] = math.sqrt(float(r @ r))
        if sines[i] > tol and len(kept) < n:
            basis[len(kept)] = r / sines[i]
            kept.append(i)
    return np.array(kept, dtype=int), sines


def pivoted_rows(rows: np.ndarray, tol: float = DEPENDENCE_TOL) -> tuple[np.ndarray, np.ndarray]:
    """The rows a pivoted choice keeps — at each step the row farthest from the span of those chosen (QR with column
    pivoting of the unit rows' transpose, LAPACK's ``geqp3``) while it is farther than ``tol`` — and their sines as
    :func:`sines_of` reports them.

    Greedy in order keeps a row as long as it is independent at all; where the kept rows drift towards dependence
    while rows dropped earlier take over (a spatial loop turning: its out-of-plane rows change from world ``y`` to
    ``x`` components), the pivoted choice keeps the well-conditioned set.
    """
    unit = _unit(rows)
    R, order = scipy.linalg.qr(unit.T, mode="r", pivoting=True)
    distance = np.abs(np.diag(R))  # of each chosen row from the span of those chosen before it
    kept = np.sort(order[: int(np.count_nonzero(distance > tol))])
    return kept, sines_of(rows, kept)


def sines_of(rows: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """Each row's sine for the choice ``kept`` (increasing indices): a kept row's against the kept rows before it
    (as :func:`independent_rows` reports it), any other row's against all kept rows."""
    unit = _unit(rows)
    sines = np.zeros(unit.shape[0])
    if not kept.size:
        return sines
    sines[kept] = independent_rows(unit[kept], tol=0.0)[1]
    basis = np.linalg.qr(unit[kept].T)[0].T
    others = np.setdiff1d(np.arange(unit.shape[0]), kept)
    rest = unit[others]
    for _ in range(2):  # twice: orthogonal to round-off
        rest = rest - (rest @ basis.T) @ basis
    sines[others] = np.linalg.norm(rest, axis=1)
    return sines


def _unit(rows: np.ndarray) -> np.ndarray:
    """The rows scaled to unit length (a zero row stays zero)."""
    rows = np.asarray(rows, dtype=float)
    norms = np.linalg.norm(rows, axis=1)
    return rows / np.where(norms > 0, norms, 1.0)[:, None]


def chosen_rows(rows: np.ndarray, tol: float = DEPENDENCE_TOL) -> tuple[np.ndarray, np.ndarray]:
    """The rows kept: greedily in declared order (:func:`independent_rows`), unless those turn nearly dependent
    (smallest sine below :data:`CLEARLY_INDEPENDENT`) where a pivoted choice of as many rows
    (:func:`pivoted_rows`) is clearly independent and :data:`SWAP_GAIN` times better conditioned — the same rank
    and, on the manifold, the same motion, without the ``1/sine`` amplification of drift. Where the rank itself
    drops (a parallelogram's collinear position: the rows' ``r``-th singular value below :data:`RANK_HOLDS`) no
    choice does better and the declared order holds."""
    kept, sines = independent_rows(rows, tol)
    if kept.size > 1 and sines[kept].min() < CLEARLY_INDEPENDENT:
        if np.linalg.svd(_unit(rows), compute_uv=False)[kept.size - 1] < RANK_HOLDS:
            return kept, sines  # the rows' rank itself is dropping (a singular position): no choice does better
        alt, alt_sines = pivoted_rows(rows, tol)
        if alt.size == kept.size and alt_sines[alt].min() >= max(SWAP_GAIN * sines[kept].min(), CLEARLY_INDEPENDENT):
            return alt, alt_sines
    return kept, sines
