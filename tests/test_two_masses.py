"""docs/theory.md §6.1: one constraint, two realizations, two motions — and every backend agrees."""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp

M1, M2, F = 1.0, 3.0, 2.0


def scene(realization: str) -> gp.scenes.Scene:
    return gp.scenes.get("two-masses", m1=M1, m2=M2, F=F, realization=realization)


def expected(realization: str) -> tuple[float, float]:
    """(acceleration of both masses, force on m1) from the closed forms of paper §1."""
    if realization == "ideal":
        acc = F / (M1 + M2)
        return acc, M1 * acc
    return F / M2, M1 * F / M2


def check(res: gp.StepResult, realization: str, rtol: float) -> None:
    acc, force_on_m1 = expected(realization)
    np.testing.assert_allclose(res.a, [acc, acc], rtol=rtol, atol=0)
    np.testing.assert_allclose(res.reaction[0], force_on_m1, rtol=rtol, atol=0)
    if realization == "servo":  # the servo multiplier itself is the follower force
        np.testing.assert_allclose(res.u, [M1 * F / M2], rtol=rtol, atol=0)
    else:  # the rod: no reaction on the sum, R = Jᵀλ with J = (−1, 1)
        np.testing.assert_allclose(res.reaction, [-res.u[0], res.u[0]], rtol=1e-15, atol=0)


@pytest.mark.parametrize("realization", ["ideal", "servo"])
def test_direct_matches_closed_form(realization: str) -> None:
    s = scene(realization)
    check(s.model.step(0.0, s.q0, s.v0, solver="direct"), realization, rtol=1e-12)


@pytest.mark.parametrize("realization", ["ideal", "servo"])
def test_default_qp_matches_closed_form(realization: str) -> None:
    s = scene(realization)
    res = s.model.step(0.0, s.q0, s.v0, solver="qp")
    assert res.solver == gp.qp.DEFAULT
    check(res, realization, rtol=1e-9)


@pytest.mark.parametrize("backend", gp.qp.names())
@pytest.mark.parametrize("realization", ["ideal", "servo"])
def test_every_installed_backend(realization: str, backend: str) -> None:
    s = scene(realization)
    res = s.model.step(0.0, s.q0, s.v0, solver="qp", backend=backend)
    # HiGHS' interior point stops at ~1e-8 here; every other backend reaches 1e-9.
    check(res, realization, rtol=1e-7 if backend.endswith("highs") else 1e-9)
    assert res.qp_residuals is not None and res.qp_residuals[0] < 1e-7


def test_the_two_realizations_give_two_motions() -> None:
    ideal, servo = scene("ideal"), scene("servo")
    a_ideal = ideal.model.step(0.0, ideal.q0, ideal.v0).a
    a_servo = servo.model.step(0.0, servo.q0, servo.v0).a
    assert abs(a_servo[0] - a_ideal[0]) > 0.1


def test_servo_reaction_is_not_ideal_and_compulsion_is_its_norm() -> None:
    s = scene("servo")
    res = s.model.step(0.0, s.q0, s.v0)
    # the servo force acts on m1 only: δx₁ = 0 are its virtual displacements
    assert res.reaction[1] == pytest.approx(0.0, abs=1e-15)
    # Z = (A⁻¹R, R) for N = 0
    assert res.compulsion == pytest.approx(res.reaction[0] ** 2 / M1, rel=1e-14)
    assert res.margin == pytest.approx(np.sqrt(M2 / (M1 + M2)), rel=1e-14)  # cos of the A⁻¹-angle between J and D


@pytest.mark.parametrize("solver", ["direct", "qp"])
@pytest.mark.parametrize("realization", ["ideal", "servo"])
def test_result_shapes(realization: str, solver: str) -> None:
    """Every field has its documented shape, even where casadi proves an entry zero."""
    s = scene(realization)
    res = s.model.step(0.0, s.q0, s.v0, solver=solver)
    n, k = 2, 1
    assert res.a.shape == res.reaction.shape == res.free_acceleration.shape == (n,)
    assert res.u.shape == res.residual.shape == res.constraint_value.shape == res.cosines.shape == (k,)
    assert abs(res.residual[0]) < 1e-15 and res.constraint_value[0] == 0.0
