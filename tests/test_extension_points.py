"""Extension points: a new lane is one row of ``lanes.LANES`` and one runner function (docs/architecture.md)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import gausspp as gp
from gausspp.simulation import integrate, lanes


def test_a_lane_registered_as_one_row_and_one_function_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """A toy lane — fixed steps from Python, through the python lane's stepping, counting its calls — registered
    in the table alone: gp.simulate(lane="toy") runs it, labels the trajectory with it, and gives the python
    lane's motion to the last bit."""
    calls = []

    def toy(job: lanes.Job):  # the one function
        calls.append(job.opts.method.name)
        return integrate.run_python(job)

    row = lanes.Lane("toy", "a toy lane", ("rk4",), (lanes.SMOOTH,), lanes.SOLVERS, runner=toy)  # the one row
    monkeypatch.setitem(lanes.LANES, "toy", row)
    scene = gp.scenes.get("pendulum")
    options = dict(method="rk4", dt=0.01, constraint_tol=1e-6)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.5, lane="toy", **options)
    reference = gp.simulate(scene.model, scene.q0, scene.v0, 0.5, lane="python", **options)
    assert calls == ["rk4"] and traj.lane == "toy" and traj.success
    np.testing.assert_array_equal(traj.q, reference.q)


def test_an_unregistered_lane_is_refused_by_name() -> None:
    scene = gp.scenes.get("pendulum")
    with pytest.raises(gp.InputError, match="toy"):
        gp.simulate(scene.model, scene.q0, scene.v0, 0.5, method="rk4", dt=0.01, lane="toy")


def test_every_built_in_lane_names_a_runner_and_a_recorder_that_exist() -> None:
    """Each row's runner and recorder resolve to functions — the events row's too: contacts go through the table."""
    import importlib

    for lane in lanes.LANES.values():
        for where in (lane.runner, lane.recorder):
            module, _, name = where.partition(":")
            assert callable(getattr(importlib.import_module(f"gausspp.simulation.{module}"), name)), lane.name


def test_a_model_with_contacts_runs_in_the_events_row_found_in_the_table(monkeypatch: pytest.MonkeyPatch) -> None:
    """The events row is a row like the others: its runner, replaced in the table, is what gp.simulate runs for a
    model with contacts."""
    from gausspp.simulation import events

    calls = []

    def counted(job: lanes.Job):
        calls.append(job.model)
        return events.run_events(job)

    monkeypatch.setitem(lanes.LANES, "events", replace(lanes.LANES["events"], runner=counted))
    scene = gp.scenes.get("block-on-floor")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.3)
    assert calls == [scene.model] and traj.lane == "events" and traj.success


# -- a QP backend: one entry of qp.REGISTERED ----------------------------------------------------------------------
def test_a_qp_backend_registered_as_one_entry_steps_and_simulates(monkeypatch: pytest.MonkeyPatch) -> None:
    """A toy backend — numpy's KKT solve of the equality form — registered by name alone: ``model.step`` and
    ``gp.simulate`` take it as ``backend=``, name it on the result, and give the direct formula's numbers."""
    from gausspp.step import qp

    calls = []

    class KKT(qp.QPBackend):
        name, description = "toy:kkt", "numpy's KKT solve"

        def solve(self, H: np.ndarray, S: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            calls.append(H.shape)
            m, k = H.shape[0], S.shape[0]
            K = np.block([[H, S.T], [S, np.zeros((k, k))]])
            x = np.linalg.lstsq(K, np.concatenate([np.zeros(m), rhs]), rcond=None)[0]
            return x[:m], x[m:]  # H u + Sᵀ y = 0, S u = rhs

    monkeypatch.setitem(qp.REGISTERED, "toy:kkt", KKT)  # the one entry
    assert "toy:kkt" in qp.names()
    scene = gp.scenes.get("pendulum")
    step = scene.model.step(0.0, scene.q0, scene.v0, solver="qp", backend="toy:kkt")
    direct = scene.model.step(0.0, scene.q0, scene.v0, solver="direct")
    assert step.solver == "toy:kkt" and calls
    np.testing.assert_allclose(step.a, direct.a, rtol=0, atol=1e-12)
    options = dict(method="rk4", dt=0.01, constraint_tol=1e-6)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.3, solver="qp", backend="toy:kkt", **options)
    reference = gp.simulate(scene.model, scene.q0, scene.v0, 0.3, solver="direct", **options)
    assert traj.success and len(calls) > 100
    np.testing.assert_allclose(traj.q, reference.q, rtol=0, atol=1e-12)


def test_an_unregistered_backend_is_refused_by_name() -> None:
    scene = gp.scenes.get("pendulum")
    with pytest.raises(gp.UnknownNameError, match="toy:kkt"):
        scene.model.step(0.0, scene.q0, scene.v0, solver="qp", backend="toy:kkt")


# -- a scene: one entry of scenes.SCENES ---------------------------------------------------------------------------
def build_toy_ring(m: float = 1.0, R: float = 0.5, t_end: float = 1.0) -> gp.scenes.Scene:
    """A bead on a vertical ring of radius R, released at the height of the centre.

    Parameters
    ----------
    m : float
        The bead's mass (kg). Allowed: > 0.
    R : float
        The ring's radius (m). Allowed: > 0.
    t_end : float
        Suggested horizon (s). Allowed: > 0.
    """
    import casadi as ca

    bead = gp.Lagrangian(2, T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2), V=lambda q, t: m * 9.81 * q[1])
    ring = gp.Holonomic(lambda q, t: ca.sqrt(q[0] ** 2 + q[1] ** 2) - R, name="ring")
    model = gp.Model(bead, [ring])
    return gp.scenes.Scene("toy-ring", model, np.array([R, 0.0]), np.zeros(2), None, t_end, None, "a bead on a ring")


def test_a_scene_registered_as_one_entry_is_listed_built_categorized_and_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """The toy ring registered by its builder alone: listed, its parameters read from the builder, built with
    them (an unknown one refused), computed to be an equality scene, simulated on its ring, and run and described
    by the command line."""
    from gausspp import cli

    monkeypatch.setitem(gp.scenes.SCENES, "toy-ring", build_toy_ring)  # the one entry
    gp.scenes.category.cache_clear()
    try:
        assert "toy-ring" in gp.scenes.names() and "toy-ring" in gp.scenes.names("equality")
        assert list(gp.scenes.parameters("toy-ring")) == ["m", "R", "t_end"]
        assert (
            gp.scenes.describe()["toy-ring"]
            == "A bead on a vertical ring of radius R, released at the height of the centre."
        )
        scene = gp.scenes.get("toy-ring", R=2.0)
        assert scene.q0[0] == 2.0
        with pytest.raises(gp.UnknownNameError, match="radius"):
            gp.scenes.get("toy-ring", radius=2.0)
        traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.5)
        assert traj.success and abs(np.hypot(*traj.q[-1]) - 2.0) <= 1e-8
        assert cli.main(["run", "toy-ring", "--t-end", "0.2"]) == 0
        assert cli.main(["scenes", "toy-ring"]) == 0
    finally:
        gp.scenes.category.cache_clear()


# -- a realization: a subclass, and one entry of REALIZATIONS to give it by name -----------------------------------
def test_a_realization_registered_as_one_entry_steps_simulates_and_verifies(monkeypatch: pytest.MonkeyPatch) -> None:
    """A toy realization — the reaction along ``2 Jᵀ``, the ideal directions scaled — written as one subclass and
    registered by name: a constraint takes it as ``realization="doubled"``; the step gives the ideal acceleration
    with half the ideal multiplier, the run the ideal motion, and ``gp.verify`` judges it a motion of that
    realization by the integral principle."""
    import casadi as ca

    from gausspp.model import realizations as R

    class Doubled(R.Realization):
        label = "doubled"

        def reaction(self, mech, c, lam):  # noqa: ANN001, ANN202
            return R.Reaction(D=2 * c.J.T, r0=ca.SX.zeros(mech.nv))

        def virtual_displacements(self, mech, c, a):  # noqa: ANN001, ANN202
            return R.VirtualDisplacements(E1=None, E0=c.J)

    monkeypatch.setitem(R.REALIZATIONS, "doubled", Doubled)  # the one entry
    bead = gp.Lagrangian(2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2), V=lambda q, t: 9.81 * q[1])

    def ring(realization: str) -> gp.Model:
        return gp.Model(bead, [gp.Holonomic(lambda q, t: q[0] ** 2 + q[1] ** 2 - 1.0, realization=realization)])

    toy, ideal = ring("doubled"), ring("ideal")
    q0, v0 = np.array([1.0, 0.0]), np.array([0.0, 0.5])
    a, b = toy.step(0.0, q0, v0), ideal.step(0.0, q0, v0)
    np.testing.assert_allclose(a.a, b.a, rtol=0, atol=1e-12)
    np.testing.assert_allclose(2 * a.u, b.u, rtol=0, atol=1e-12)
    traj = gp.simulate(toy, q0, v0, 1.0)
    reference = gp.simulate(ideal, q0, v0, 1.0)
    assert traj.success
    np.testing.assert_allclose(traj.q, reference.q, rtol=0, atol=1e-10)
    assert gp.verify(toy, traj).is_motion
    along_x = gp.Model(
        bead,
        [gp.Holonomic(lambda q, t: q[0] ** 2 + q[1] ** 2 - 1.0, realization=R.Force(M=lambda q, v, t: [[1.0, 0.0]]))],
    )
    assert not gp.verify(along_x, traj).is_motion  # control: not a motion of a force along x


def test_a_wrong_registration_is_refused_by_name(monkeypatch: pytest.MonkeyPatch) -> None:
    """A registry entry that does not make what it should is a project error naming it, not a traceback."""
    from gausspp.model import realizations as R
    from gausspp.step import qp

    monkeypatch.setitem(qp.REGISTERED, "toy:wrong", lambda: "not a backend")
    with pytest.raises(gp.InputError, match="toy:wrong"):
        qp.get("toy:wrong")
    monkeypatch.setitem(R.REALIZATIONS, "wrong", lambda: 3)
    with pytest.raises(gp.InputError, match="'wrong'"):
        gp.Holonomic(lambda q, t: q[0], realization="wrong")
    monkeypatch.setitem(gp.scenes.SCENES, "wrong", 5)
    with pytest.raises(gp.InputError, match="'wrong'"):
        gp.scenes.get("wrong")
