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
the kinetic metric ``A⁻¹``) of the span of the rows kept before it. The answer is then exactly the
motion of the minimal model made of the kept rows — at any drift, not only to within it.
"""

from __future__ import annotations

import math

import numpy as np

#: A row whose normalized residual against the rows kept before it (sine of the angle between the row
#: and their span, in the metric A⁻¹) is below this, at the reference state, is dependent on them.
DEPENDENCE_TOL = 1e-7
#: Rows whose smallest sine at the actual state exceeds this are independent whatever the drift: no
#: reference state is needed (drift of 1e-3 moves a sine by about that much).
CLEARLY_INDEPENDENT = 1e-2


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
