"""Random mechanisms (issue 28, item 4): hypothesis builds them — random mass matrices, constraint rows and
reaction directions, nearly singular and badly scaled ones among them — and every step is either a gausspp
error or an answer that agrees with the acceleration-space QP assembled from the problem's data alone
(:func:`gausspp.acceleration_qp`), by both solvers. Never another exception.

The mechanism: ``T = ½ vᵀ A v`` with a constant ``A`` (condition number and scale drawn), a constant force ``f``,
and ``k`` velocity-level rows ``Φ = J v − c`` realized ideally (``D = Jᵀ``) or by forces along ``Mᵀ``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gausspp as gp


def spd(rng: np.random.Generator, n: int, condition: float, scale: float) -> np.ndarray:
    """A symmetric positive-definite matrix with the given condition number and size."""
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    eigenvalues = scale * np.geomspace(1.0, condition, n)
    A = (Q * eigenvalues) @ Q.T
    return 0.5 * (A + A.T)


def mechanism(A: np.ndarray, f: np.ndarray) -> gp.Lagrangian:
    Adm, fdm = ca.DM(A), ca.DM(f)
    return gp.Lagrangian(n=A.shape[0], T=lambda q, v, t: 0.5 * ca.dot(v, Adm @ v), F=lambda q, v, t: fdm)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@pytest.mark.filterwarnings("ignore::gausspp.GaussppWarning")  # a small margin is warned about: an answer too
@given(
    n=st.integers(2, 5),
    k=st.integers(1, 3),
    seed=st.integers(0, 2**20),
    condition=st.sampled_from([1.0, 1e3, 1e6, 1e10]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    realization=st.sampled_from(["ideal", "force", "nearly dependent rows", "force nearly A-orthogonal"]),
)
def test_a_random_step_is_the_acceleration_qp_or_a_gausspp_error(
    n: int, k: int, seed: int, condition: float, scale: float, realization: str
) -> None:
    k = min(k, n - 1)
    rng = np.random.default_rng(seed)
    A = spd(rng, n, condition, scale)
    f = scale * rng.standard_normal(n)
    J = rng.standard_normal((k, n))
    if realization == "nearly dependent rows" and k > 1:
        J[-1] = J[0] + 1e-9 * rng.standard_normal(n)
    c = rng.standard_normal(k)
    M = None
    if realization.startswith("force"):
        M = J + 0.3 * rng.standard_normal((k, n))
        if realization == "force nearly A-orthogonal":  # J A⁻¹ Mᵀ nearly singular
            null = np.linalg.svd(J @ np.linalg.inv(A))[2][-1]
            M[0] = null + 1e-10 * rng.standard_normal(n)
    Jdm, cdm = ca.DM(J), ca.DM(c)
    Mdm = None if M is None else ca.DM(M)
    how = gp.Ideal() if Mdm is None else gp.Force(lambda q, v, t: Mdm)
    q = rng.standard_normal(n)
    v = np.linalg.lstsq(J, c, rcond=None)[0]  # on the constraint
    try:
        model = gp.Model(mechanism(A, f), gp.Constraint(lambda q, v, t: Jdm @ v - cdm, name="rows", realization=how))
        data = model.evaluate_data(0.0, q, v, np.zeros(0))
        reference = gp.acceleration_qp(data.A, np.linalg.solve(data.A, data.f + data.r0), data.J, data.phi, data.D)
    except gp.GaussppError:
        return  # a refusal is an answer; a foreign exception fails the test
    size = np.abs(reference.a).max() + np.abs(np.linalg.solve(A, f)).max()
    well_posed = condition <= 1e6 and realization in ("ideal", "force")
    for solver in ("qp", "direct"):
        try:
            result = model.step(0.0, q, v, solver=solver)
        except gp.GaussppError:
            assert not (well_posed and realization == "ideal"), f"{solver} refused a well-posed ideal step"
            continue
        assert np.all(np.isfinite(result.a))
        if well_posed and result.margin > 1e-3:
            assert np.abs(result.a - reference.a).max() <= 1e-6 * size, solver


def test_the_comparison_fails_on_a_wrong_answer() -> None:
    """The control: the same comparison rejects an acceleration with the reaction halved."""
    rng = np.random.default_rng(1)
    A, f, J = spd(rng, 4, 10.0, 1.0), rng.standard_normal(4), rng.standard_normal((2, 4))
    c = rng.standard_normal(2)
    Jdm, cdm = ca.DM(J), ca.DM(c)
    model = gp.Model(mechanism(A, f), gp.Constraint(lambda q, v, t: Jdm @ v - cdm, name="rows"))
    q, v = rng.standard_normal(4), np.linalg.lstsq(J, c, rcond=None)[0]
    data = model.evaluate_data(0.0, q, v, np.zeros(0))
    reference = gp.acceleration_qp(data.A, np.linalg.solve(data.A, data.f), data.J, data.phi, data.D)
    result = model.step(0.0, q, v)
    size = np.abs(reference.a).max() + np.abs(np.linalg.solve(A, f)).max()
    assert np.abs(result.a - reference.a).max() <= 1e-9 * size
    wrong = np.linalg.solve(A, f + 0.5 * (A @ result.a - f))
    assert np.abs(wrong - reference.a).max() > 1e-6 * size
