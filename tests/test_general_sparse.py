"""The sparse route of the compiled general step (gausspp.step.general.sparse_pattern): a large redundant linkage's
step in its own sparsity, checked from the problem's data alone and against the Python step.

The ladder of four double-parallelogram cells (39 coordinates, 42 rows of rank 38: every third bar's rows are
redundant) is the case; states come from a run up to just before the first collinear position (t = 0.708 s) and
are perturbed off the manifold by hypothesis.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp import c_code, scenes
from gausspp.scenes import parallelogram
from gausspp.step.data import NO_STAB
from gausspp.step.general import general_step, sparse_pattern
from gausspp.step.general.solve import CONSISTENCY_TOL

from .test_general_compiled import optimality_gap

CELLS = 4


@functools.cache
def ladder() -> tuple[gp.Model, dict, np.ndarray, np.ndarray, np.ndarray]:
    sc = scenes.get("parallelogram", cells=CELLS, third_bar=True)
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.6, rtol=1e-11, atol=1e-12, record=np.linspace(0.0, 0.6, 13))
    return sc.model, sc.params, traj.t, traj.q, traj.v


def call_at(model: gp.Model, t: float, q: np.ndarray, v: np.ndarray):
    """The compiled call's result at the state (the Python step decided the pattern first), or None."""
    lam = np.zeros(0)
    general_step.solve_at(model, t, q, v, lam, None)
    fast = general_step.compiled_outputs(model, t, q, v, lam, None, stab=NO_STAB, consistency_tol=CONSISTENCY_TOL)
    return None if fast is None else (fast[0], general_step.result_of(model, t, *fast))


def test_a_large_redundant_linkage_takes_the_sparse_route_and_a_small_one_does_not() -> None:
    model, _, T, Q, V = ladder()
    call, _ = call_at(model, float(T[1]), Q[1], V[1])
    assert call.sparse and call.least_norm and call.redundant == CELLS
    small = scenes.get("four-bar-redundant")
    general_step.solve_at(small.model, 0.0, small.q0, small.v0, np.zeros(0), None)
    assert not general_step.current_call(small.model, None, None, CONSISTENCY_TOL).sparse


def test_the_sparse_step_is_the_gauss_qp_at_every_sample() -> None:
    """From the data alone (numpy): the motion equation, every row kept — the dropped ones too — and stationarity;
    the acceleration and the reaction agree with the Python step (which shares no factorization with it)."""
    model, _, T, Q, V = ladder()
    lam = np.zeros(0)
    for i in range(T.size):
        t, q, v = float(T[i]), Q[i], V[i]
        answer = call_at(model, t, q, v)
        assert answer is not None, f"the sparse call's flag is down on the manifold at t={t}"
        result = answer[1]
        reference = general_step.solve_at(model, t, q, v, lam, None, compiled=False)[0]
        assert optimality_gap(model, t, q, v, lam, result, None) < 1e-9
        scale = np.abs(reference.a).max() + np.abs(reference.free_acceleration).max()
        assert np.abs(result.a - reference.a).max() < 1e-10 * scale
        assert np.abs(result.reaction - reference.reaction).max() < 1e-9 * (1 + np.abs(reference.reaction).max())
        assert result.disagreement(reference) < 1e-9  # a and u: the least-norm split of the reaction, as there
        assert result.margin == 0.0  # redundant rows


def test_a_long_ladder_leaves_the_reaction_on_its_kept_rows() -> None:
    """Beyond LEAST_NORM_ROWS dropped rows the split is the kept rows' (the dropped rows' multipliers 0): the
    reaction and the acceleration are still the Gauss step's, from the data alone."""
    cells = sparse_pattern.LEAST_NORM_ROWS + 2
    sc = scenes.get("parallelogram", cells=cells, third_bar=True)
    call, result = call_at(sc.model, 0.0, sc.q0, sc.v0)
    assert call.sparse and not call.least_norm and call.redundant == cells
    assert (result.u == 0).sum() == cells  # the dropped rows'
    assert optimality_gap(sc.model, 0.0, sc.q0, sc.v0, np.zeros(0), result, None) < 1e-9


def test_the_data_check_fails_on_a_wrong_sparse_answer() -> None:
    """Negative control: the kept rows' reaction halved, or a dropped row's multiplier moved without the
    acceleration following, fails the check from the data alone."""
    model, _, T, Q, V = ladder()
    t, q, v, lam = float(T[5]), Q[5], V[5], np.zeros(0)
    result = call_at(model, t, q, v)[1]
    d = model.evaluate_data(t, q, v, lam)
    u = result.u * 0.5
    halved = type(result).of_fields({**result.__dict__, "a": np.linalg.solve(d.A, d.f + d.r0 + d.D @ u), "u": u})
    assert optimality_gap(model, t, q, v, lam, halved, None) > 1e-3
    moved = result.u.copy()
    moved[np.argmax(result.u == 0)] += np.abs(result.u).max()  # a dropped row's multiplier, the motion unchanged
    inconsistent = type(result).of_fields({**result.__dict__, "u": moved})
    assert optimality_gap(model, t, q, v, lam, inconsistent, None) > 1e-3


@settings(max_examples=30, deadline=None)
@given(
    where=st.integers(0, 12),
    size=st.sampled_from([0.0, 1e-12, 1e-9, 1e-6, 1e-3]),
    seed=st.integers(0, 2**16),
)
def test_off_the_manifold_the_sparse_step_answers_as_the_python_step(where: int, size: float, seed: int) -> None:
    """Drifted states: where the flag is up, the acceleration is the Python step's; model.step always is."""
    model, _, T, Q, V = ladder()
    rng = np.random.default_rng(seed)
    t, lam = float(T[where]), np.zeros(0)
    q = Q[where] + size * rng.standard_normal(Q.shape[1])
    v = V[where] + size * rng.standard_normal(V.shape[1])
    try:
        reference = general_step.solve_at(model, t, q, v, lam, None, compiled=False)[0]
    except gp.GaussppError as exc:
        with pytest.raises(type(exc)):
            general_step.solve_at(model, t, q, v, lam, None)
        return
    scale = np.abs(reference.a).max() + np.abs(reference.free_acceleration).max()
    answer = call_at(model, t, q, v)
    if answer is not None:
        assert np.abs(answer[1].a - reference.a).max() < 1e-7 * scale
    routed = model.step(t, q, v, lam)
    assert np.abs(routed.a - reference.a).max() < 1e-7 * scale


def test_the_sparse_route_changes_no_trajectory(monkeypatch: pytest.MonkeyPatch) -> None:
    """0.6 s of the ladder at rtol = 1e-12: the sparse route's run is the dense route's (measured 2e-13 m) and the
    one-degree-of-freedom reference's."""
    sc = scenes.get("parallelogram", cells=CELLS, third_bar=True)
    times = np.linspace(0.0, 0.6, 7)
    options = dict(rtol=1e-12, atol=1e-12, record=times)
    sparse = gp.simulate(sc.model, sc.q0, sc.v0, 0.6, **options)
    monkeypatch.setattr(sparse_pattern, "applies", lambda *args: False)
    dense_scene = scenes.get("parallelogram", cells=CELLS, third_bar=True)  # a new model: nothing compiled for it
    dense = gp.simulate(dense_scene.model, dense_scene.q0, dense_scene.v0, 0.6, **options)
    assert sparse.success and dense.success
    np.testing.assert_allclose(sparse.q, dense.q, rtol=0, atol=1e-10)
    theta, omega = parallelogram.one_dof_reference(times, **sc.params)
    ref = np.array([parallelogram.maximal_state(a, b, 0.0, CELLS, True)[0] for a, b in zip(theta, omega, strict=True)])
    assert np.abs(sparse.q - ref).max() < 1e-9


@pytest.mark.skipif(c_code.compiler() is None, reason="no C compiler")
def test_the_general_step_generated_as_c_answers_as_the_virtual_machine() -> None:
    """Model(codegen=True): the compiled general call runs as C (c_code), with the same answer."""
    sc = scenes.get("parallelogram", third_bar=True)
    model = gp.Model(sc.model.mechanism, list(sc.model.constraints), codegen=True)
    result = model.step(0.0, sc.q0, sc.v0)
    call = general_step.current_call(model, None, None, CONSISTENCY_TOL)
    assert call is not None and not call.function.is_a("SXFunction")  # the external C library's function
    again = model.step(0.0, sc.q0, sc.v0)  # through the C call
    reference = sc.model.step(0.0, sc.q0, sc.v0)
    assert again.disagreement(reference) < 1e-12 and result.disagreement(reference) < 1e-12
