"""Extension points: a new lane is one row of ``lanes.LANES`` and one runner function (docs/architecture.md)."""

from __future__ import annotations

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


def test_every_built_in_lane_names_a_runner_that_exists() -> None:
    """Each row's runner resolves to a function (the events row excepted: contacts enter gp.simulate first)."""
    import importlib

    for lane in lanes.LANES.values():
        if lane.name == "events":
            assert lane.runner == ""
            continue
        module, _, name = lane.runner.partition(":")
        assert callable(getattr(importlib.import_module(f"gausspp.simulation.{module}"), name)), lane.name
