"""The sparse step route (gausspp/step/equality/sparse.py) against the dense one: the same step on every scene and
on chains.

The two routes share the model's expressions and nothing of the elimination: the dense route whitens the reaction
space with Cholesky factors of ``J A⁻¹ Jᵀ`` and ``Dᵀ A⁻¹ D``, the sparse one factors ``A`` and ``S = J A⁻¹ D``
with casadi's sparse LDLᵀ/QR. Their outputs must agree to round-off (1e-10 relative), for the direct solution and
for the QP, on every realization the scenes have (ideal, servo, inertial with λ, vakonomic, mixed, redundant).
"""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp.step.equality import sparse

FIELDS = ("a", "u", "reaction", "compulsion", "S_norm", "residual", "a_free", "qdot", "power_reaction")
# servo scenes: no one-step solution; robot scenes: the robots extra (tests/test_robot_scenes.py)
ONE_STEP = [n for n in gp.scenes.names() if n not in gp.scenes.names("servo") + gp.scenes.names("robot")]
SCENES = [n for n in ONE_STEP if not (gp.scenes.get(n).model.contacts or gp.scenes.get(n).model.bounded)]
#: Scenes whose rows are redundant at their initial state (J A⁻¹ D singular): no direct step, the QP steps them.
REDUNDANT = ("four-bar-redundant", "spatial-parallelogram")


def with_route(model: gp.Model, route: str) -> gp.Model:
    """The same model with its step eliminated by ``route``."""
    return gp.Model(
        model.mechanism,
        [*model.constraints, *model.contacts],
        margin_warn=model.margin_warn,
        margin_error=model.margin_error,
        refine=model.refine,
        contact_tol=model.contact_tol,
        route=route,
    )


def outputs(model: gp.Model, solver: str, q: np.ndarray, v: np.ndarray, lam: np.ndarray) -> dict[str, np.ndarray]:
    out = model.kernel(solver)(0.0, q, v, lam, np.zeros(2))
    return {name: np.array(value, copy=True) for name, value in out.items()}


def agree(x: dict[str, np.ndarray], y: dict[str, np.ndarray], rtol: float = 1e-10) -> bool:
    """Every field within ``rtol`` of the larger of its size and the free acceleration's (the step's scale)."""
    scale = max(np.abs(y["a_free"]).max(initial=0.0), np.abs(y["a"]).max(initial=0.0), 1.0)
    for name in FIELDS:
        size = max(np.abs(y[name]).max(initial=0.0), scale if name in ("a", "residual", "qdot") else 1.0)
        if x[name].shape != y[name].shape or not np.all(np.abs(x[name] - y[name]) <= rtol * size):
            return False
    return (x["pivot"] > 0) == (y["pivot"] > 0)


def state(scene: gp.scenes.Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lam = scene.lam0 if scene.lam0 is not None else np.zeros(scene.model.n_lam)
    return np.asarray(scene.q0, float), np.asarray(scene.v0, float), np.asarray(lam, float)


@pytest.mark.parametrize("solver", ["direct", "qp"])
@pytest.mark.parametrize("name", SCENES)
def test_sparse_and_dense_routes_agree_on_every_scene(name: str, solver: str) -> None:
    scene = gp.scenes.get(name)
    if solver == "direct" and scene.model.k != scene.model.m:
        pytest.skip("no direct solution: more reaction unknowns than rows")
    dense, sparse_ = with_route(scene.model, "dense"), with_route(scene.model, "sparse")
    assert (dense.route, sparse_.route) == ("dense", "sparse")
    q, v, lam = state(scene)
    if name in REDUNDANT:  # no step of its own (S singular): both routes hand it to the general QP
        if solver == "direct":
            for model in (dense, sparse_):
                with pytest.raises(gp.RealizabilityError, match="needs independent rows"):
                    model.step(0.0, q, v, lam, solver="direct")
        else:
            got, ref = sparse_.step(0.0, q, v, lam), dense.step(0.0, q, v, lam)
            assert got.solver == ref.solver and np.allclose(got.a, ref.a, rtol=1e-10, atol=1e-10)
        return
    reference = outputs(dense, solver, q, v, lam)
    got = outputs(sparse_, solver, q, v, lam)
    assert agree(got, reference), name
    wrong = {**got, "a": got["a"] * (1 + 1e-8) + 1e-8}
    assert not agree(wrong, reference)  # the comparison sees a wrong acceleration


def chain(n: int) -> gp.scenes.Scene:
    return gp.scenes.get("planar-chain", N=n)


@pytest.mark.parametrize("n", [1, 2, 5, 16])
@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_sparse_and_dense_routes_agree_on_chains(n: int, solver: str) -> None:
    scene = chain(n)
    q, v, lam = state(scene)
    rng = np.random.default_rng(n)
    v = v + 0.3 * rng.standard_normal(v.size)  # moving, and off the velocity constraint: a general state
    reference = outputs(with_route(scene.model, "dense"), solver, q, v, lam)
    assert agree(outputs(with_route(scene.model, "sparse"), solver, q, v, lam), reference)


def test_auto_takes_the_sparse_route_for_many_rows_and_says_so() -> None:
    assert gp.scenes.get("pendulum").model.route == "dense"  # two rows: the dense route's robustness
    big = chain(8).model
    assert big.k == 16 and big.route == "sparse" and big.route_requested == "auto"
    traj = gp.simulate(big, chain(8).q0, chain(8).v0, 0.02, dt=1e-3, method="rk4", solver="direct")
    assert traj.route == "sparse" and traj.lane == "compiled" and traj.status == "success"
    assert with_route(big, "dense").route == "dense"
    with pytest.raises(gp.UnknownNameError, match="route='fast' is unknown"):
        with_route(big, "fast")


def test_a_dense_mass_matrix_keeps_the_dense_route() -> None:
    """Many rows on a mass matrix with no zero entry (one body coupling all coordinates): nothing to exploit."""
    n = 10
    C = np.eye(n) + 0.1
    body = gp.Lagrangian(n=n, T=lambda q, v, t: 0.5 * sum(C[i, j] * v[i] * v[j] for i in range(n) for j in range(n)))
    rows = [gp.Constraint(lambda q, v, t, i=i: v[i] - v[i + 1], name=f"c{i}") for i in range(sparse.SPARSE_FROM_ROWS)]
    assert gp.Model(body, rows).route == "dense"


def test_the_sparse_step_through_model_step_and_the_hot_path() -> None:
    scene = chain(6)
    model = scene.model
    q, v, _ = state(scene)
    for solver in ("direct", "qp"):
        result = model.step(0.0, q, v, solver=solver)
        reference = with_route(model, "dense").step(0.0, q, v, solver=solver)
        assert np.allclose(result.a, reference.a, rtol=1e-10, atol=1e-10 * np.abs(reference.free_acceleration).max())
        assert result.margin == pytest.approx(reference.margin, rel=1e-10)


def test_margins_of_large_banded_symmetric_S_match_the_svd() -> None:
    """The recorded margin of a long chain comes from the band of S (O(k b²)); it is the SVD's smallest value."""
    from gausspp.step.realizability import BANDED_FROM_ROWS, stacked_margins

    scene = chain(24)  # 48 rows ≥ BANDED_FROM_ROWS
    model = scene.model
    assert model.k >= BANDED_FROM_ROWS
    traj = gp.simulate(model, scene.q0, scene.v0, 0.2, dt=1e-3, method="rk4", solver="direct", record=40)
    S = np.stack(
        [
            model.kernel("direct")(t, q, v, np.zeros(0), np.zeros(2))["S_norm"].copy()
            for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)
        ]
    )
    reference = np.linalg.svd(S, compute_uv=False)[:, -1]
    got = stacked_margins(S, model.k, model.m)
    eps = np.finfo(float).eps
    assert np.all(np.abs(got - reference) <= 50 * model.k * eps)
    assert np.allclose(traj.margin, reference, rtol=0, atol=50 * model.k * eps)
    assert not np.all(np.abs(got * (1 + 1e-6) - reference) <= 50 * model.k * eps)  # a wrong margin would show


def test_all_cosines_of_a_long_chain_step_are_the_svd_of_its_S() -> None:
    scene = chain(20)  # 40 rows: the band's eigenvalues, not a dense SVD
    model = scene.model
    result = model.step(0.0, scene.q0, scene.v0, solver="direct")
    S = model.kernel("direct")(0.0, scene.q0, scene.v0, np.zeros(0), np.zeros(2))["S_norm"]
    reference = np.linalg.svd(S, compute_uv=False)
    tolerance = 50 * model.k * np.finfo(float).eps * reference[0]
    assert result.cosines.shape == reference.shape and np.all(np.abs(result.cosines - reference) <= tolerance)
    assert result.margin == result.cosines[-1]
    assert not np.all(np.abs(np.sort(result.cosines) - reference) <= tolerance)  # the order (largest first) matters


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_the_sparse_refinement_keeps_r0_against_the_reference(solver: str) -> None:
    """The sparse route's refinement (run where ``A`` is not a constant, well-conditioned matrix: here symbolic)
    with a known reaction part ``r₀ ≠ 0`` and ``cond A = 1e3``, against ``gp.acceleration_qp`` from the numbers
    alone. Measured 1e-13 relative; a refinement that dropped ``r₀`` is off by 2e-2 … 4.6 (the mutation check)."""
    import casadi as ca

    from gausspp.step import qp
    from gausspp.step.equality.expressions import StepExpressions
    from gausspp.step.equality.kernel import build_kernel

    from .factories import random_spd

    n, k = 6, 3
    A, f, r0 = ca.SX.sym("A", n, n), ca.SX.sym("f", n), ca.SX.sym("r0", n)
    J, phi, D = ca.SX.sym("J", k, n), ca.SX.sym("phi", k), ca.SX.sym("D", n, k)
    p = StepExpressions(A=A, f=f, r0=r0, J=J, phi=phi, D=D, Phi=ca.SX.zeros(k))
    backend = qp.get(None) if solver == "qp" else None
    kernel = build_kernel("sparse_refine", [A, f, r0, J, phi, D], p, solver, backend, refine=True, route="sparse")
    rng = np.random.default_rng(29)
    for _ in range(20):
        An = random_spd(rng, n, 3.0)
        fn, r0n, Jn = rng.standard_normal(n), rng.standard_normal(n), rng.standard_normal((k, n))
        phin, Dn = rng.standard_normal(k), rng.standard_normal((n, k))
        out = kernel(An, fn, r0n, Jn, phin, Dn)
        a = np.asarray(out["a"], float).ravel()
        ref = gp.acceleration_qp(An, np.linalg.solve(An, fn + r0n), Jn, phin, Dn).a
        assert np.abs(a - ref).max() <= 1e-9 * np.abs(ref).max()
        without = gp.acceleration_qp(An, np.linalg.solve(An, fn), Jn, phin, Dn).a  # negative control: r₀ dropped
        assert np.abs(without - ref).max() > 1e-6 * np.abs(ref).max()
