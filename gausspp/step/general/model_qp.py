"""The model's step at one state as one :class:`~gausspp.step.general.GaussProblem`.

The bilateral rows enter as equalities (or, for bounded servos, as rows to *track* with the
reaction inside its bounds); the closed unilateral contacts as ``J_c q̈ ≥ φ_c`` with a force
``λ_c ≥ 0`` along ``J_cᵀ`` (docs/theory.md §6).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...workspace import workspace
from ..protocol import StepModel
from .solve import GaussProblem


def closed_rows(model: StepModel, gc: np.ndarray, closed: Any) -> np.ndarray:
    """Contact rows taken as closed: those given, else those within ``contact_tol`` of zero."""
    return np.flatnonzero(gc <= model.contact_tol) if closed is None else np.asarray(closed, dtype=int)


@dataclass(frozen=True)
class _Rows:
    """What the problem's rows and unknowns are for one set of closed contacts (the same at every state)."""

    role: tuple[str, ...]
    lower: np.ndarray  # read-only
    upper: np.ndarray  # read-only
    names: tuple[str, ...]


def _rows(model: StepModel, closed: np.ndarray) -> _Rows:
    m, nc = model.m, closed.size
    lower, upper = np.full(m + nc, -np.inf), np.full(m + nc, np.inf)
    lower[m:] = 0.0
    role = ["eq"] * model.k + ["ge"] * nc
    for grp, bounds in zip(model.groups, model.group_bounds, strict=True):
        if bounds is not None:
            lower[grp.cols], upper[grp.cols] = bounds
            role[grp.rows] = ["track"] * (grp.rows.stop - grp.rows.start)
    lower.flags.writeable = upper.flags.writeable = False
    return _Rows(tuple(role), lower, upper, (*model.row_names, *(model.contact_row_names[i] for i in closed)))


def gauss_problem(
    model: StepModel,
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
    m, k, nc, nv = model.m, model.k, closed.size, model.nv
    rows = workspace(model).get(("gauss-rows", closed.tobytes()), lambda: _rows(model, closed))
    D, J = D.reshape(nv, m), J.reshape(k, nv)
    if nc:
        Jcc = Jc[closed].reshape(nc, nv)
        D, J, phi = np.hstack([D, Jcc.T]), np.vstack([J, Jcc]), np.concatenate([phi.ravel(), phi_c])
    return GaussProblem(
        A=A,
        a0=a0,
        D=D,
        J=J,
        phi=phi.ravel(),
        role=rows.role,
        lower=rows.lower,
        upper=rows.upper,
        rows=rows.names,
        t=t,
    )
