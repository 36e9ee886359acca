"""The step by the general Gauss QP: contacts, bounded actuators, redundant rows.

:func:`solve_at` evaluates the model's :class:`~gausspp.step.data.StepData`, poses the step as one
:class:`~gausspp.step.general.GaussProblem` (:mod:`gausspp.step.gauss_problem`), lets
:func:`~gausspp.step.general.solve_general` solve it — deciding redundancy at the nearest state on
the manifold (:mod:`gausspp.step.manifold`) — and packages the answer as a :class:`StepResult`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import InputError, NonFiniteError
from .. import dense
from ..data import NO_STAB, StepData, evaluate
from ..protocol import StepModel
from ..realizability import normalized_cosines
from ..results import StepResult
from .manifold import on_manifold, reference_problem
from .model_qp import closed_rows, gauss_problem
from .solve import CONSISTENCY_TOL, GaussProblem, GaussSolution, check_backend, solve_general


def _check_contacts(model: StepModel, t: float, d: StepData, closed: np.ndarray) -> None:
    approaching = closed[d.gdotc[closed] < -model.contact_tol]
    if approaching.size:
        i = int(approaching[0])
        raise InputError(
            f"contact {model.contact_row_names[i]!r} is closed and approaching (ġ = {d.gdotc[i]:.3g}) at t={t:.6g}: "
            "the velocities must jump first — apply model.impact(...) or simulate, which does"
        )
    if not np.isfinite(d.A).all() or not np.isfinite(d.f + d.r0).all():
        raise NonFiniteError(f"the mass matrix or the forces are not finite at t={t:.6g}; check the model there")


def _problem(model: StepModel, t: float, d: StepData, closed: np.ndarray) -> tuple[GaussProblem, np.ndarray]:
    """The problem, and the free acceleration ``A⁻¹ f`` (both solves on one factorization of ``A``)."""
    try:
        a0, free = dense.solve(d.A, np.column_stack([d.f + d.r0, d.f])).T
    except np.linalg.LinAlgError:
        a0 = free = np.zeros(model.nv)  # the QP's Cholesky reports the singular A
    return gauss_problem(model, t, d.A, a0, d.J, d.phi, d.D, d.Jc, d.phic[closed], closed), free


def _result(
    model: StepModel,
    t: float,
    d: StepData,
    problem: GaussProblem,
    free: np.ndarray,
    sol: GaussSolution,
    closed: np.ndarray,
    backend: str | None,
) -> StepResult:
    m, k = model.m, model.k
    contact_force = np.zeros(len(model.contact_row_names))
    contact_force[closed] = sol.u[m:]
    cos, margin = normalized_cosines(sol.S_norm[:k, :m], d.D)
    return StepResult(
        t=t,
        a=sol.a,
        u=sol.u[:m],
        reaction=d.r0 + problem.D @ sol.u,  # the realizations' reactions and the contact forces
        compulsion=sol.compulsion,
        margin=margin,
        cosines=cos,
        residual=sol.residual[:k],
        constraint_value=d.Phi,
        free_acceleration=free,
        solver=f"gauss-qp:{check_backend(backend)}",
        contact_force=contact_force,
        tracking_error=sol.tracking_error,
        saturated=sol.at_bound[:m],
    )


def solve_at(
    model: StepModel,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    lam: np.ndarray,
    backend: str | None,
    stab: Any = NO_STAB,
    closed: Any = None,
    consistency_tol: float = CONSISTENCY_TOL,
) -> tuple[StepResult, GaussSolution, dict[str, np.ndarray]]:
    """The general step on checked inputs: the result, the QP's solution, and what a simulation records.

    The third item holds ``qdot``, ``energy``, ``power_forces``, ``power_reaction``, ``g`` and ``S_norm``
    (the normalized ``J A⁻¹ D`` of the bilateral rows), named as the compiled kernels name them.
    """
    d = evaluate(model, t, q, v, lam, stab)
    closed = closed_rows(model, d.gc, closed)
    _check_contacts(model, t, d, closed)
    problem, free = _problem(model, t, d, closed)
    sol = solve_general(
        problem,
        backend,
        consistency_tol,
        reference=lambda: reference_problem(model, t, q, v, lam, stab, closed),
        # a state on the constraints is itself the witness that dependent rows hold together
        near_manifold=lambda: on_manifold(model, d.J, d.Phi, d.g, q, v),
    )
    result = _result(model, t, d, problem, free, sol, closed, backend)
    extras = {
        "qdot": d.qdot,
        "energy": np.array([d.energy]),
        "power_forces": np.array([d.power]),
        "power_reaction": np.array([float(v @ result.reaction)]),
        "g": d.g,
        "S_norm": sol.S_norm[: model.k, : model.m],
    }
    return result, sol, extras
