"""The generalized Gauss principle on random systems (docs/theory.md §3), QP ≡ direct.

Random SPD A (condition number up to 1e6), random J (k×n), D (n×k) and r₀, n ≤ 12, k ≤ 4.
Draws whose realizability margin is below 1e-3 are set aside (``assume``): there the
step itself is ill-posed and both solvers inherit its condition number; the margin's own
behaviour is tested in test_realizability.py.
"""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp.step.realizability import cosines

from .factories import random_spd

problems = st.tuples(
    st.integers(1, 12),  # n
    st.integers(1, 4),  # k
    st.floats(0.0, 6.0),  # log10 cond(A)
    st.integers(0, 2**32 - 1),  # seed
)


def make(n: int, k: int, log10_cond: float, seed: int) -> gp.StepProblem:
    k = min(k, n)
    rng = np.random.default_rng(seed)
    return gp.StepProblem.create(
        A=random_spd(rng, n, log10_cond),
        f=rng.standard_normal(n),
        J=rng.standard_normal((k, n)),
        phi=rng.standard_normal(k),
        D=rng.standard_normal((n, k)),
        r0=rng.standard_normal(n),
    )


def test_reported_compulsion_is_gauss_compulsion(rng: np.random.Generator) -> None:
    """StepResult.compulsion = (A(a − a₀), a − a₀) on well-conditioned random systems."""
    for _ in range(50):
        n = int(rng.integers(2, 9))
        k = int(rng.integers(1, n))
        p = make(n, k, 2.0, int(rng.integers(0, 2**32 - 1)))
        if cosines(p.A, p.J, p.D).min() < 1e-2:
            continue
        res = gp.solve(p, solver="qp")
        assert abs(compulsion(p, res.a) - res.compulsion) <= 1e-10 * res.compulsion


def rel(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.max(np.abs(x - y)) / max(np.max(np.abs(y)), 1e-300))


def compulsion(p: gp.StepProblem, a: np.ndarray) -> float:
    """Z(a) = (A(a − a₀), a − a₀), a₀ = A⁻¹(f + r₀), computed independently of the library."""
    d = a - np.linalg.solve(p.A, p.f + p.r0)
    return float(d @ p.A @ d)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(problems)
def test_qp_equals_direct(args: tuple[int, int, float, int]) -> None:
    p = make(*args)
    assume(cosines(p.A, p.J, p.D).min() > 1e-3)
    direct = gp.solve(p, solver="direct")
    gauss = gp.solve(p, solver="qp")
    assert rel(gauss.a, direct.a) < 1e-8
    assert rel(gauss.u, direct.u) < 1e-8
    # and both keep the constraint J a = φ (checked on each: the two share the reduction, so their agreement alone
    # is no evidence — tests/test_step_reference.py compares every route with the independent gp.acceleration_qp)
    assert rel(p.J @ direct.a, p.phi) < 1e-8
    assert rel(p.J @ gauss.a, p.phi) < 1e-8


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(problems, st.integers(0, 2**32 - 1))
def test_pythagoras_and_least_compulsion(args: tuple[int, int, float, int], wseed: int) -> None:
    """For every conceivable w (Dᵀw = 0): Z(a + w) = Z(a) + (Aw, w) ≥ Z(a)."""
    p = make(*args)
    assume(cosines(p.A, p.J, p.D).min() > 1e-3)
    res = gp.solve(p, solver="qp")
    assert rel(p.J @ res.a, p.phi) < 1e-8  # the answer is feasible: the identity below is about feasible points
    n, m = p.D.shape
    if n == m:
        return  # no conceivable variation: Dᵀw = 0 forces w = 0 (tests/test_step_reference.py has larger sets)
    rng = np.random.default_rng(wseed)
    null = np.linalg.svd(p.D.T)[2][m:].T  # orthonormal basis of ker Dᵀ
    w = null @ rng.standard_normal(null.shape[1]) * rng.uniform(1e-3, 1e3)
    Aww = float(w @ p.A @ w)
    Z_a, Z_aw = compulsion(p, res.a), compulsion(p, res.a + w)
    # the cross term 2(A(a − a₀), w) = 2 uᵀDᵀw vanishes up to round-off in its factors
    roundoff = 1e-12 * (Z_a + Aww + np.linalg.norm(p.D @ res.u) * np.linalg.norm(w))
    assert abs(Z_aw - (Z_a + Aww)) <= roundoff
    assert Z_a <= Z_aw + roundoff
