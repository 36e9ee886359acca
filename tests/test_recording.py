"""The recording of smooth runs: all samples at once (the step mapped over them) gives what sample by sample gives."""

import numpy as np
import pytest

import gausspp as gp
from gausspp.simulation import recording
from gausspp.simulation.drift import Stabilization
from gausspp.simulation.rhs import RightHandSide
from gausspp.simulation.samples import Samples

COLUMNS = ("a", "u", "reaction", "compulsion", "residual", "g", "margin", "energy", "q", "v", "lam")


class OneByOne(RightHandSide):
    """The same right-hand side, recorded sample by sample (nothing evaluated at once)."""

    def evaluate_all(self, t, y, solutions=None):
        return {}, np.zeros(0), 0


def samples_of(model, traj):
    work_forces = np.nan_to_num(traj.work_forces)
    y = np.column_stack([traj.q, traj.v, traj.lam, traj.work_reaction, work_forces])
    return Samples(traj.t, y, traj.steps, traj.rhs_evaluations, None, traj.method, traj.solver)


def both(model, samples, solver):
    at_once = recording.record_smooth(model, RightHandSide(model, solver, None, Stabilization()), samples, 1e-3)
    one_by_one = recording.record_smooth(model, OneByOne(model, solver, None, Stabilization()), samples, 1e-3)
    return at_once, one_by_one


SCENES = {"pendulum": {}, "gyrostat": {}, "planar-chain": {"N": 16}}  # the chain: sparse route, banded margins


@pytest.mark.parametrize("scene", sorted(SCENES))
@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_at_once_equals_sample_by_sample(scene, solver):
    sc = gp.scenes.get(scene, **SCENES[scene])
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.5, dt=1e-3, method="rk4", lane="compiled", solver=solver, record=5)
    assert traj.status == "success" and traj.t.size > 50
    (fast, fast_failure, notes), (slow, slow_failure, slow_notes) = both(sc.model, samples_of(sc.model, traj), solver)
    assert fast_failure is None and slow_failure is None and notes == slow_notes
    for name in COLUMNS:
        np.testing.assert_allclose(getattr(fast, name), getattr(slow, name), rtol=1e-12, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(getattr(fast, name), getattr(traj, name), rtol=1e-12, atol=1e-12, err_msg=name)


def test_a_failing_sample_fails_as_sample_by_sample():
    sc = gp.scenes.get("gyrostat")
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.2, dt=1e-2, method="rk4", lane="compiled", solver="direct")
    samples = samples_of(sc.model, traj)
    samples.y[7, 0] = np.nan  # a sample the step cannot evaluate: the recording stops there, as before
    (fast, fast_failure, _), (slow, slow_failure, _) = both(sc.model, samples, "direct")
    assert type(fast_failure) is type(slow_failure) and str(fast_failure) == str(slow_failure)
    assert fast.t.size == slow.t.size == 7
    np.testing.assert_allclose(fast.a, slow.a, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("scene", ["pendulum", "gyrostat"])
def test_a_compiled_qp_run_is_recorded_by_replaying_its_own_qp_solutions(scene):
    """The run hands each sample's QP solution to the recording, which replays the step from it (no QP solved
    again): the same columns as solving each sample's QP anew; a wrong solution would show."""
    sc = gp.scenes.get(scene)
    model = sc.model
    traj = gp.simulate(model, sc.q0, sc.v0, 0.3, dt=1e-3, method="rk4", lane="compiled", solver="qp", record=7)
    samples = samples_of(model, traj)
    from gausspp.simulation.compiled import integrate_compiled
    from gausspp.simulation.inputs import check_options
    from gausspp.simulation.methods import get as method

    y0 = samples.y[0]
    opts = check_options(
        model,
        method=method("rk4"),
        t0=0.0,
        t_end=0.3,
        dt=1e-3,
        solver="qp",
        backend=None,
        rtol=1e-8,
        atol=1e-8,
        record=7,
        constraint_tol=1e-8,
        throw=True,
        rest_speed=0.0,
        max_events=1000,
        lane="compiled",
    )
    t, y, *_, solutions = integrate_compiled(model, opts, stab=Stabilization(), y0=y0)
    assert solutions is not None and np.isfinite(solutions[:-1]).all() and np.isnan(solutions[-1]).all()
    rhs = RightHandSide(model, "qp", None, Stabilization())
    replayed, _, good = rhs.evaluate_all(t, y, solutions)
    solved, _, good_solved = rhs.evaluate_all(t, y)
    assert good == good_solved == t.size
    for name in ("a", "u", "reaction", "compulsion", "residual", "qp_primal"):
        np.testing.assert_allclose(replayed[name], solved[name], rtol=1e-12, atol=1e-13, err_msg=name)
    wrong, _, _ = rhs.evaluate_all(t, y, solutions * (1 + 1e-6))
    assert not np.allclose(wrong["a"], solved["a"], rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_the_mapped_step_stores_s_by_its_nonzeros_in_the_right_places(solver):
    """The recording's mapped step keeps the normalized S by its nonzeros and scatters them into each sample's
    matrix; that matrix is the single step's (dense) S at the same state, sample by sample."""
    sc = gp.scenes.get("planar-chain", N=16)
    assert sc.model.route == "sparse"
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.05, dt=1e-3, method="rk4", solver=solver, record=5)
    rhs = RightHandSide(sc.model, solver, None, Stabilization())
    y = samples_of(sc.model, traj).y
    out, _, good = rhs.evaluate_all(traj.t, y)
    assert good == traj.t.size and np.count_nonzero(out["S_norm"][0]) < out["S_norm"][0].size / 4  # banded
    single = np.array([np.array(rhs.evaluate(t, yi)["S_norm"]).reshape(out["S_norm"].shape[1:]) for t, yi in
                       zip(traj.t, y, strict=True)])  # fmt: skip
    np.testing.assert_allclose(out["S_norm"], single, rtol=0.0, atol=1e-13)
    swapped = out["S_norm"][::-1]  # negative control: another sample's S is told apart
    assert np.abs(swapped - single).max() > 1e-6


def test_a_symmetric_s_is_known_from_the_expressions():
    from gausspp.step.realizability import stacked_margins

    for name, params, symmetric in (
        ("planar-chain", {"N": 3}, True),
        ("pendulum", {}, True),
        ("two-masses", {"realization": "ideal"}, True),
        ("two-masses", {"realization": "servo"}, False),
        ("gyrostat", {}, False),
    ):
        assert gp.scenes.get(name, **params).model.symmetric_S is symmetric, (name, params)
    rng = np.random.default_rng(3)
    B = rng.normal(size=(6, 4, 4))
    S = B @ B.transpose(0, 2, 1)  # symmetric: the eigenvalue route gives the SVD's smallest singular value
    np.testing.assert_allclose(stacked_margins(S, 4, 4, symmetric=True), np.linalg.svd(S)[1][:, -1], rtol=1e-10)
    assert not np.allclose(stacked_margins(B, 4, 4, symmetric=True), np.linalg.svd(B)[1][:, -1], rtol=1e-3)


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_the_recording_takes_whole_chunks_then_short_ones_sample_by_sample_right(solver):
    """201 samples: one call over CHUNK = 128 samples, then five over TAIL_CHUNK = 16 (the last padded) — each
    sample's step the single step's at its state, the samples in order."""
    from gausspp.simulation.rhs import CHUNK, TAIL_CHUNK

    sc = gp.scenes.get("pendulum")
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.2, dt=1e-3, method="rk4", solver=solver)
    assert traj.t.size > CHUNK and (traj.t.size - CHUNK) % TAIL_CHUNK  # a padded tail call
    rhs = RightHandSide(sc.model, solver, None, Stabilization())
    y = samples_of(sc.model, traj).y
    out, margin, good = rhs.evaluate_all(traj.t, y)
    assert good == traj.t.size
    states = zip(traj.t, y, strict=True)
    single = np.array([rhs.evaluate(t, yi, stabilized=False)["a"].ravel().copy() for t, yi in states])
    scale = np.abs(single).max()
    np.testing.assert_allclose(out["a"][:, :, 0], single, rtol=0, atol=1e-12 * scale)
    shifted = np.roll(out["a"][:, :, 0], 1, axis=0)  # negative control: a sample's step is told from its neighbour's
    assert np.abs(shifted - single).max() > 1e-6 * scale


def test_the_places_of_stored_entries_follow_casadis_column_major_order():
    """_places maps a mapped output's nonzeros to (sample, row, column), for a pattern that is not symmetric."""
    import casadi as ca

    from gausspp.simulation.rhs import CHUNK, _places

    rng = np.random.default_rng(5)
    blocks = []
    for _ in range(CHUNK):
        block = np.zeros((3, 4))
        block[0, 1], block[2, 0], block[1, 3], block[2, 3] = rng.normal(size=4) + 5.0  # nonzero, not symmetric
        blocks.append(block)
    stacked = ca.sparsify(ca.DM(np.hstack(blocks)))  # the samples' blocks side by side, as a mapped output
    sample, row, col = _places(stacked.sparsity(), CHUNK)
    rebuilt = np.zeros((CHUNK, 3, 4))
    rebuilt[sample, row, col] = np.asarray(stacked.nonzeros())
    np.testing.assert_array_equal(rebuilt, np.array(blocks))
    rebuilt_wrong = np.zeros((CHUNK, 3, 4))
    rebuilt_wrong[sample, row[::-1], col] = np.asarray(stacked.nonzeros())[: row.size]  # negative control
    assert not np.array_equal(rebuilt_wrong, np.array(blocks))
