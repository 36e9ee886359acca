"""The impact of ideal rows as one verified QP in ``v⁺`` (:mod:`gausspp.step.impact_qp`) against the general step.

The reference is the general Gauss step (:func:`gausspp.step.general.solve_general`: scaled, staged, its own
rank decisions) on the problem built from the impact's data; the verification is shown to refuse wrong answers.
"""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp
from gausspp.step import impact_qp
from gausspp.step.data import evaluate
from gausspp.step.general import solve_general
from gausspp.step.general.model_qp import closed_rows, gauss_problem


def _impact_states(name: str) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """The states just before each impact of a 3 s run of the scene."""
    scene = gp.scenes.get(name)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 3.0, lam0=scene.lam0)
    times = sorted({e["t"] for e in traj.events if e["kind"] == "impact"})
    first = [int(np.flatnonzero(traj.t == t)[0]) for t in times]  # the sample before the jump comes first
    return [(float(traj.t[i]), traj.q[i], traj.v[i]) for i in first]


def _general_step(model: gp.Model, t: float, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(v⁺, impulses of the closed contacts)`` by the general step, from the model's data alone."""
    d = evaluate(model, t, q, v, np.zeros(model.n_lam))
    closed = closed_rows(model, d.gc, None)
    e = model.restitution[closed]
    Jcc = d.Jc[closed].reshape(closed.size, model.nv)
    target = -e * np.minimum(d.gdotc[closed], 0.0)
    problem = gauss_problem(
        model, t, d.A, v, d.J, d.J @ v - d.Phi, d.D, d.Jc, Jcc @ v - d.gdotc[closed] + target, closed
    )
    sol = solve_general(problem, None)
    return sol.a, sol.u[model.m :]


@pytest.mark.parametrize("name", ["block-on-floor", "bouncing-pendulum"])
def test_the_fast_impact_is_the_general_steps(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every impact of a 3 s run: the QP in v⁺ answers (not the fallback), and v⁺ and the impulses are the
    general route's to 1e-12 (measured ≤ 2e-14)."""
    model = gp.scenes.get(name).model
    answered: list[bool] = []
    original = impact_qp.ideal_impact

    def spy(*args: object, **kwargs: object) -> object:
        out = original(*args, **kwargs)  # type: ignore[arg-type]
        answered.append(out is not None)
        return out

    monkeypatch.setattr(impact_qp, "ideal_impact", spy)
    states = _impact_states(name)
    assert states
    for t, q, v in states:
        answered.clear()
        fast = model.impact(t, q, v)
        assert answered == [True]
        v_ref, p_ref = _general_step(model, t, q, v)
        scale = 1.0 + np.abs(v).max()
        np.testing.assert_allclose(fast.v_after, v_ref, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(fast.impulse[fast.closed], p_ref, rtol=0, atol=1e-12 * scale)


def test_the_verification_refuses_wrong_answers() -> None:
    """The block's first impact: the true answer passes; a velocity off by 1e-6, an impulse of the wrong sign, a
    contact left penetrating, an impulse on a separating contact each fail."""
    model = gp.scenes.get("block-on-floor").model
    t, q, v = _impact_states("block-on-floor")[0]
    d = evaluate(model, t, q, v, np.zeros(0))
    closed = closed_rows(model, d.gc, None)
    Jcc = d.Jc[closed].reshape(closed.size, model.nv)
    target = Jcc @ v - d.gdotc[closed] - model.restitution[closed] * np.minimum(d.gdotc[closed], 0.0)
    e = d.J @ v - d.Phi
    x, mu, p = impact_qp.ideal_impact(model, None, d.A, v, d.J, e, Jcc, target)  # type: ignore[misc]
    assert impact_qp.verified(d.A, v, d.J, e, Jcc, target, x, mu, p)
    assert not impact_qp.verified(d.A, v, d.J, e, Jcc, target, x + 1e-6, mu, p)
    assert not impact_qp.verified(d.A, v, d.J, e, Jcc, target, x, mu, -p - 1e-3)
    assert not impact_qp.verified(d.A, v, d.J, e, Jcc, target, v, mu, 0 * p)  # no impulse: still approaching
    lifted = target - 1.0  # every contact already leaves faster than needed: an impulse there is wrong
    assert not impact_qp.verified(d.A, v, d.J, e, Jcc, lifted, x, mu, p + 1.0)


def test_a_rejected_answer_falls_back_to_the_general_step(monkeypatch: pytest.MonkeyPatch) -> None:
    """With the verification failing every time, the general step answers and the impact is the same."""
    model = gp.scenes.get("block-on-floor").model
    t, q, v = _impact_states("block-on-floor")[0]
    fast = model.impact(t, q, v)
    monkeypatch.setattr(impact_qp, "verified", lambda *args: False)
    slow = model.impact(t, q, v)
    np.testing.assert_allclose(slow.v_after, fast.v_after, rtol=0, atol=1e-12 * (1 + np.abs(v).max()))


def test_rows_that_are_not_ideal_take_the_general_step() -> None:
    """A realization with its own reaction direction (the crane's servo) is not the QP in v⁺ alone."""
    assert not impact_qp.applies(gp.scenes.get("crane").model)
    assert impact_qp.applies(gp.scenes.get("block-on-floor").model)
