"""The checked step's hot path (gausspp/step/equality/checked_call.py): the same answer as the full step, every
check kept.

``model.step`` answers from one buffer-bound call when the state is an array of the right shape and every
check passes in the graph (an all-clear flag); otherwise the full step (``checked_step``) answers. These tests
compare the two routes on every scene the hot path serves, and probe each check with an input that must fail
it — including NaN in a coordinate the step's graph never reads. The closed-form cosines of one or two rows
are compared with numpy's SVD, and each comparison is shown to fail on a deliberately wrong answer.
"""

from __future__ import annotations

import math
import warnings

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp.step.equality import checked
from gausspp.step.realizability import graph_cosines

FIELDS = ("a", "u", "reaction", "residual", "constraint_value", "free_acceleration", "cosines")
SCENES = ("pendulum", "two-masses", "rigid-body-servo", "gyrostat", "skate", "andrews", "mixed-rate", "planar-chain")
#: Parameters of the scenes above where the default does not exercise a route (the chain: sparse, banded S)
PARAMS = {"planar-chain": {"N": 16}}


def graph_values(S: np.ndarray) -> np.ndarray:
    k, m = S.shape
    X = ca.SX.sym("S", k, m)
    return np.array(ca.Function("cos", [X], [graph_cosines(X, k, m)])(S)).ravel()


def agree_with_svd(got: np.ndarray, S: np.ndarray) -> bool:
    """Within 50 ε of the largest singular value (the SVD's own accuracy class)."""
    ref = np.linalg.svd(S, compute_uv=False)
    return got.shape == ref.shape and bool(np.all(np.abs(got - ref) <= 50 * np.finfo(float).eps * max(ref[0], 1e-300)))


matrices = st.tuples(
    st.integers(1, 2), st.integers(1, 4), st.integers(0, 2**32 - 1), st.sampled_from([0.0, 1e-15, 1e-9, 1e-4, 1.0])
)


@settings(max_examples=150, deadline=None)
@given(matrices)
def test_closed_form_cosines_match_the_svd(case: tuple[int, int, int, float]) -> None:
    k, m, seed, spread = case
    rng = np.random.default_rng(seed)
    S = rng.standard_normal((k, m)) * 10.0 ** rng.uniform(-3, 3)
    if k == 2:  # second row nearly the first: the smallest value is nearly 0 (the case that matters)
        S[1] = S[0] * (1 + spread) + spread * rng.standard_normal(m) * np.linalg.norm(S[0])
    assert agree_with_svd(graph_values(S), S)


def test_closed_form_cosines_on_orthonormal_and_zero_rows() -> None:
    Q = np.linalg.qr(np.random.default_rng(3).standard_normal((3, 3)))[0][:2]  # equal values: g = 0
    assert agree_with_svd(graph_values(Q), Q)
    assert np.all(graph_values(np.zeros((2, 3))) == 0)


def test_the_cosine_comparison_fails_on_a_wrong_answer() -> None:
    S = np.array([[1.0, 0.3, 0.0], [1.0, 0.3 + 1e-7, 1e-8]])
    got = graph_values(S)
    assert agree_with_svd(got, S)
    wrong = got.copy()
    wrong[-1] += 1e-13  # far below the margins that matter, far above the SVD's accuracy here
    assert not agree_with_svd(wrong, S)
    # the textbook σ₂² = λ_min(S Sᵀ) = (tr − √(tr² − 4 det)) / 2 loses σ₂ to cancellation: the check sees it
    G = S @ S.T
    tr, det = np.trace(G), G[0, 0] * G[1, 1] - G[0, 1] ** 2
    textbook = np.sqrt(
        np.maximum([(tr + math.sqrt(tr * tr - 4 * det)) / 2, (tr - math.sqrt(tr * tr - 4 * det)) / 2], 0)
    )
    assert not agree_with_svd(textbook, S)


def same(fast: gp.StepResult, full: gp.StepResult) -> bool:
    """Each field equal to round-off, relative to the field's size (and the free acceleration for ``a``)."""
    for name in FIELDS:
        x, y = getattr(fast, name), getattr(full, name)
        scale = max(np.max(np.abs(y), initial=0.0), np.max(np.abs(full.free_acceleration), initial=0.0), 1.0)
        if x.shape != y.shape or not np.all(np.abs(x - y) <= 1e-12 * scale):
            return False
    return (
        math.isclose(fast.compulsion, full.compulsion, rel_tol=1e-10, abs_tol=1e-14)
        and math.isclose(fast.margin, full.margin, rel_tol=1e-12)
        and fast.solver == full.solver
        and (fast.qp_residuals is None) == (full.qp_residuals is None)
        and fast.contact_force.size == 0
        and fast.tracking_error == 0.0
        and fast.saturated is None
    )


def full_step(model: gp.Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray | None, solver: str):
    t, q, v, lam = model.checked_state(t, q, v, lam)
    return checked.checked_step(model, t, q, v, lam, solver, None, model.refine)


@pytest.mark.parametrize("solver", ["direct", "qp"])
@pytest.mark.parametrize("name", SCENES)
def test_the_hot_path_answers_as_the_full_step(name: str, solver: str) -> None:
    scene = gp.scenes.get(name, **PARAMS.get(name, {}))
    model, q, v = scene.model, np.asarray(scene.q0, float), np.asarray(scene.v0, float)
    lam = scene.lam0 if getattr(scene, "lam0", None) is not None else None
    hot = checked.checked_call(model, solver, None, model.refine)
    assert hot is not None
    fast = hot(0.0, q, v, None if lam is None else np.asarray(lam, float))
    assert fast is not None, "the hot path declined a plain, valid state"
    full = full_step(model, 0.0, q, v, lam, solver)
    assert same(fast, full)
    assert same(model.step(0.0, q, v, lam, solver=solver), full)
    assert fast == fast and isinstance(fast, gp.StepResult)  # a dataclass like any other result
    wrong = gp.StepResult(**{**vars(full), "a": full.a + 1e-9 * (1 + np.abs(full.a))})
    assert not same(wrong, full)  # the comparison sees a wrong acceleration


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-0.3, 0.3), min_size=6, max_size=6))
def test_off_the_manifold_both_routes_agree_or_both_refuse(offset: list[float]) -> None:
    """Perturbed states (off the constraint): the hot path answers as the full step, or leaves it to it."""
    scene = gp.scenes.get("pendulum")
    model = scene.model
    q = np.asarray(scene.q0, float) + np.array(offset[: model.nq])
    v = np.asarray(scene.v0, float) + np.array(offset[model.nq : model.nq + model.nv])
    for solver in ("direct", "qp"):
        fast = checked.checked_call(model, solver, None, model.refine)(0.0, q, v, None)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                full = full_step(model, 0.0, q, v, None, solver)
        except gp.GaussppError:
            assert fast is None
        else:
            assert fast is None or same(fast, full)


def free_x() -> gp.Model:
    """A particle on the line ``y = 0``: ``x`` enters no formula of the step."""
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2))
    return gp.Model(body, gp.Holonomic(lambda q, t: q[1], name="floor"))


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_nan_in_a_coordinate_the_graph_never_reads_is_still_refused(solver: str) -> None:
    model = free_x()
    ok = model.step(0.0, np.array([1.0, 0.0]), np.zeros(2), solver=solver)
    assert np.all(np.isfinite(ok.a))
    for q, v in ((np.array([np.nan, 0.0]), np.zeros(2)), (np.zeros(2), np.array([np.inf, 0.0]))):
        assert checked.checked_call(model, solver, None, model.refine)(0.0, q, v, None) is None
        with pytest.raises(gp.NonFiniteError, match="contains NaN or inf"):
            model.step(0.0, q, v, solver=solver)
    with pytest.raises(gp.NonFiniteError, match="t is not finite"):
        model.step(math.nan, np.zeros(2), np.zeros(2), solver=solver)


def test_other_inputs_take_the_full_step_with_its_errors() -> None:
    scene = gp.scenes.get("pendulum")
    model, q, v = scene.model, np.asarray(scene.q0, float), np.asarray(scene.v0, float)
    hot = checked.checked_call(model, "direct", None, model.refine)
    ref = model.step(0.0, q, v, solver="direct")
    for q_in in (q.tolist(), q[None, :], q.astype(int)):  # a list, a (1, n) array, integers
        assert hot(0.0, q_in, v, None) is None
        assert same(model.step(0.0, q_in, v, solver="direct"), ref)
    assert same(hot(0.0, q.astype(np.float32), v, None), ref)  # float32 holds these values exactly
    with pytest.raises(gp.ShapeError, match="q has 2 entries, expected 3"):
        model.step(0.0, q[:2], v, solver="direct")
    with pytest.raises(gp.InputError, match="t must be a number"):
        model.step("now", q, v, solver="direct")
    with pytest.raises(gp.UnknownNameError, match="solver='fast' is unknown"):
        model.step(0.0, q, v, solver="fast")


def test_a_small_margin_is_left_to_the_full_step_which_warns() -> None:
    """A servo whose force is nearly tangent to its constraint: margin 1e-7 < margin_warn = 1e-6."""
    body = gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2))
    servo = gp.Constraint(lambda q, v, t: v[1], name="servo", realization=gp.Force(lambda q, v, t: [1.0, 1e-7]))
    model = gp.Model(body, servo)
    state = (0.0, np.zeros(2), np.array([1.0, 0.0]), None)
    assert checked.checked_call(model, "direct", None, model.refine)(*state) is None
    with pytest.warns(gp.RealizabilityWarning, match="realizability margin 1e-07"):
        result = model.step(*state[:3], solver="direct")
    assert result.margin == pytest.approx(1e-7, rel=1e-6)


def test_results_do_not_share_memory() -> None:
    """Each result owns its numbers: a later step does not change an earlier result."""
    scene = gp.scenes.get("pendulum")
    model, q, v = scene.model, np.asarray(scene.q0, float), np.asarray(scene.v0, float)
    first = model.step(0.0, q, v, solver="direct")
    a = first.a.copy()
    model.step(0.0, q + 0.1, v + 0.5, solver="direct")
    assert np.array_equal(first.a, a)
    with pytest.raises(ValueError):
        first.contact_force[...] = 1.0  # the shared empty array is read-only
