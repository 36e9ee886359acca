"""Solving a step given as numbers, without a model: :func:`solve`.

It takes a :class:`~gausspp.step.data.StepProblem` (``A, f, r₀, J, φ, D`` of docs/theory.md §2 at one instant,
what :meth:`Model.step_data` returns), so users (and the property tests) can pose a step from matrices they
already have. It compiles one kernel per shape and solver, the same code a model's step runs.
"""

from __future__ import annotations

import functools

import casadi as ca

from ...errors import InputError
from .. import qp
from ..data import StepProblem
from ..outcome import Where, evaluation_failed, to_result
from ..protocol import Group
from ..results import StepResult
from ..solvers import check_solver
from .expressions import StepExpressions
from .kernel import Kernel, build_kernel

__all__ = ["StepProblem", "solve"]


@functools.lru_cache(maxsize=64)
def _kernel(n: int, k: int, m: int, solver: str, backend: str | None) -> Kernel:
    A, f, r0 = ca.SX.sym("A", n, n), ca.SX.sym("f", n), ca.SX.sym("r0", n)
    J, phi, D = ca.SX.sym("J", k, n), ca.SX.sym("phi", k), ca.SX.sym("D", n, m)
    p = StepExpressions(A=A, f=f, r0=r0, J=J, phi=phi, D=D, Phi=ca.SX.zeros(k))
    return build_kernel("problem", [A, f, r0, J, phi, D], p, solver, qp.get(backend) if solver == "qp" else None)


def solve(
    problem: StepProblem,
    solver: str = "qp",
    backend: str | None = None,
    *,
    margin_warn: float = 1e-6,
    margin_error: float = 1e-12,
) -> StepResult:
    """Solve one step given as numbers, by the direct formula or the Gauss QP.

    Same checks and result as :meth:`Model.step`; constraint rows are named ``row i``.
    """
    if not isinstance(problem, StepProblem):
        raise InputError(
            f"solve: give a gp.StepProblem (gp.StepProblem.create(A, f, J, phi, D) or model.step_data), got "
            f"{type(problem).__name__}"
        )
    # its arrays checked against each other (a problem edited with dataclasses.replace skips create's checks)
    problem = StepProblem.create(problem.A, problem.f, problem.J, problem.phi, problem.D, problem.r0)
    n, k, m = problem.shape
    check_solver(solver, backend)
    name = qp.get(backend).name if solver == "qp" else None
    kernel = _kernel(n, k, m, solver, name)
    p = problem
    groups = [Group(f"row {i}", slice(i, i + 1), slice(i, i + 1) if m == k else slice(0, m), "") for i in range(k)]
    where = Where(0.0, name or "direct", groups, lambda: problem)
    try:
        out = kernel(p.A, p.f, p.r0, p.J, p.phi, p.D)
    except RuntimeError as exc:
        raise evaluation_failed(exc, where, margin_error=margin_error) from None
    return to_result(out, where, margin_warn=margin_warn, margin_error=margin_error)
