"""A QP answer is accepted only if it is optimal: the dual residual is checked as well as the primal one."""

from __future__ import annotations

import numpy as np
import pytest
import qpsolvers

import gausspp as gp
from gausspp.step.general import GaussProblem, solve_general


def _problem() -> GaussProblem:
    """Over-actuated: one row, two force directions, so the feasible set is a line and optimality matters."""
    A = np.diag([1.0, 2.0, 3.0])
    return GaussProblem(
        A=A,
        a0=np.array([0.0, -1.0, 0.5]),
        D=np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
        J=np.array([[1.0, 1.0, 0.0]]),
        phi=np.array([0.3]),
        role=["eq"],
        lower=np.full(2, -np.inf),
        upper=np.full(2, np.inf),
    )


def test_a_feasible_but_not_optimal_answer_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """A backend double that returns a feasible point off the optimum, with the optimum's multipliers."""
    backend = "daqp" if "daqp" in qpsolvers.available_solvers else "osqp"
    right = solve_general(_problem(), backend)
    real_solve = qpsolvers.solve_problem

    def feasible_but_wrong(problem, solver, **options):
        sol = real_solve(problem, solver=solver, **options)
        if problem.A is not None and problem.A.shape[0] == 1:  # move along the feasible line
            null = np.linalg.svd(np.atleast_2d(problem.A.toarray() if hasattr(problem.A, "toarray") else problem.A))[2][
                -1
            ]
            sol.x = sol.x + 0.5 * null
        return sol

    monkeypatch.setattr(qpsolvers, "solve_problem", feasible_but_wrong)
    with pytest.raises(gp.QPSolveError, match="not optimal.*dual residual"):
        solve_general(_problem(), backend)
    monkeypatch.undo()
    assert np.allclose(solve_general(_problem(), backend).a, right.a, rtol=1e-12, atol=1e-14)


def test_the_compiled_step_refuses_a_large_dual_residual() -> None:
    """The compiled QP's own outputs, with the dual residual replaced by a large one: refused; as computed: kept."""
    from gausspp.step.outcome import Where, to_result

    scene = gp.scenes.get("two-masses", realization="servo")
    model = scene.model
    out = dict(model.kernel("qp")(0.0, scene.q0, scene.v0, np.zeros(model.n_lam), np.zeros(2)))
    where = Where(0.0, "casadi:qrqp", model.groups, lambda: model.step_data(0.0, scene.q0, scene.v0))
    assert float(out["qp_dual"][0]) < 1e-12
    assert to_result(out, where, margin_warn=1e-6, margin_error=1e-12).a.shape == (2,)
    out["qp_dual"] = np.array([1e-3])
    with pytest.raises(gp.QPSolveError, match="dual residual"):
        to_result(out, where, margin_warn=1e-6, margin_error=1e-12)
