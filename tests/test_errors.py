"""Bad input gets a project error that names the culprit (issue 2, item 7)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.step.qp import QPBackend


def masses(realization: gp.Realization | None = None, m1: float = 1.0, m2: float = 3.0) -> gp.Model:
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * m1 * v[0] ** 2 + 0.5 * m2 * v[1] ** 2, F=lambda q, v, t: [0, 2])
    return gp.Model(body, gp.Constraint(lambda q, v, t: v[1] - v[0], name="rod", realization=realization))


def test_wrong_state_shape() -> None:
    with pytest.raises(gp.ShapeError, match=r"q has 3 entries, expected 2"):
        masses().step(0.0, [0, 0, 0], [0, 0])
    with pytest.raises(gp.ShapeError, match=r"v has 1 entries, expected 2"):
        masses().step(0.0, [0, 0], [0])


def test_wrong_expression_shape() -> None:
    with pytest.raises(gp.ShapeError, match=r"F\(q, v, t\) returned shape"):
        gp.Lagrangian(n=2, T=lambda q, v, t: ca.sumsqr(v), F=lambda q, v, t: [1, 2, 3])
    with pytest.raises(gp.ShapeError, match=r"Force: M\(q, v, t\) returned shape"):
        masses(gp.Force(M=lambda q, v, t: [1, 0, 0]))
    with pytest.raises(gp.ShapeError, match=r"T\(q, v, t\) could not be evaluated"):
        gp.Lagrangian(n=2, T=lambda q, v, t: v[5] ** 2)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_state(bad: float) -> None:
    with pytest.raises(gp.NonFiniteError, match=r"v contains NaN or inf at t=0.5"):
        masses().step(0.5, [0, 0], [bad, 0])
    with pytest.raises(gp.NonFiniteError, match="t is not finite"):
        masses().step(bad, [0, 0], [0, 0])


def test_non_finite_model_output_is_located() -> None:
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), F=lambda q, v, t: [ca.log(q[0]), 0])
    model = gp.Model(body, gp.Constraint(lambda q, v, t: v[1] - v[0], name="rod"))
    with pytest.raises(gp.NonFiniteError, match=r"forces F − h is not finite at t=1"):
        model.step(1.0, [-1.0, 0.0], [0.0, 0.0])


def test_mass_matrix_not_positive_definite() -> None:
    mech = gp.MassMatrix(n=2, A=lambda q, t: [[1.0, 0.0], [0.0, q[0]]], f=lambda q, v, t: [0, 0])
    model = gp.Model(mech, gp.Constraint(lambda q, v, t: v[0] + v[1], name="c"))
    assert model.step(0.0, [2.0, 0.0], [0.0, 0.0]).margin == pytest.approx(1.0)
    for solver in ("direct", "qp"):
        with pytest.raises(gp.NotPositiveDefiniteError, match=r"not positive definite at t=0.3: eigenvalues \[-0.5"):
            model.step(0.3, [-0.5, 0.0], [0.0, 0.0], solver=solver)


def test_mass_matrix_not_symmetric() -> None:
    mech = gp.MassMatrix(n=2, A=lambda q, t: [[1.0, 0.1], [0.0, 1.0]], f=lambda q, v, t: [0, 0])
    model = gp.Model(mech, gp.Constraint(lambda q, v, t: v[0] + v[1], name="c"))
    with pytest.raises(gp.NotPositiveDefiniteError, match="not symmetric"):
        model.step(0.0, [0, 0], [0, 0])


def test_inertia_not_positive_definite() -> None:
    with pytest.raises(gp.InputError, match="inertia must be positive definite"):
        gp.RigidBody(inertia=np.diag([1.0, -2.0, 3.0]))


def test_unrealizable_constraint_names_time_constraint_and_fix() -> None:
    # pushing both equal masses equally cannot change their relative velocity
    model = masses(gp.Force(M=lambda q, v, t: [1, 1]), m1=2.0, m2=2.0)
    with pytest.raises(gp.RealizabilityError) as info:
        model.step(0.37, [0, 0], [0, 0], solver="direct")
    msg = str(info.value)
    assert "'rod'" in msg and "t=0.37" in msg and "force realization" in msg and "choose force directions M" in msg
    assert info.value.constraint == "rod" and info.value.margin < 1e-12


def test_unknown_backend_lists_valid_names() -> None:
    with pytest.raises(
        gp.UnknownNameError, match=r"QP backend 'gurobix' is unknown; valid names here: \[.*casadi:osqp"
    ):
        masses().step(0.0, [0, 0], [0, 0], backend="gurobix")
    with pytest.raises(gp.UnknownNameError, match="solver='newton' is unknown"):
        masses().step(0.0, [0, 0], [0, 0], solver="newton")


def test_N_not_affine_in_velocities() -> None:
    with pytest.raises(gp.NotAffineError, match=r"Inertial: N\(q, v, t\) must be affine in the velocities"):
        masses(gp.Inertial(N=lambda q, v, t: v[0] ** 2, lam0=0.0))
    with pytest.raises(gp.NotAffineError, match=r"unnamed Constraint .*: Φ\(q, v, t\) must be affine"):
        gp.Model(  # every velocity-level constraint, whatever its realization
            gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v)),
            gp.Constraint(lambda q, v, t: v[0] ** 2 - v[1], realization=gp.Vakonomic(lam0=0.0)),
        )


def test_missing_lam0() -> None:
    model = masses(gp.Inertial(N=lambda q, v, t: v[0]))
    with pytest.raises(gp.MissingMultiplierError, match=r"\['rod'\] carry λ as a state.*lam0"):
        model.step(0.0, [0, 0], [0, 0])
    assert model.step(0.0, [0, 0], [0, 0], lam=[0.5]).u.shape == (1,)  # given explicitly: fine
    with pytest.raises(gp.ShapeError, match="lam0 has 2 entries, expected 1"):
        masses(gp.Inertial(N=lambda q, v, t: v[0], lam0=[1.0, 2.0]))


def test_failed_qp_is_reported() -> None:
    class Broken(QPBackend):
        name = "broken"

        def solve(self, H, S, rhs):  # noqa: ANN001, ANN201
            return np.zeros(H.shape[0]), np.zeros(S.shape[0])  # ignores the constraint

    with pytest.raises(gp.QPSolveError, match=r"QP backend broken did not solve the step at t=0.1"):
        masses().step(0.1, [0, 0], [0, 0], backend=Broken())
