"""Machines of the zoo dropped on the floor through ``gp.simulate`` with hard frictional contacts (issue 43).

hopper, walker2d, half_cheetah and ant (Gymnasium's files) from MuJoCo's reference pose (limited joints moved into
their ranges) above the floor, zero control, 2 s: no contact point below the floor by more than 1e-9 m, the
energy never rising (beyond round-off of its own size), and the machine at rest on the floor at the end; beside
each, how deep MuJoCo's soft contacts (its own file: integrator, timestep, solref) let the same feet sink.
"""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import gausspp as gp

from .mjcf_zoo import zoo

pytestmark = [
    pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs MuJoCo: pip install mujoco"),
    pytest.mark.skipif(zoo() is None, reason="MuJoCo's model collections are not on this machine"),
]

DROPPED = ["gymnasium/hopper.xml", "gymnasium/walker2d.xml", "gymnasium/half_cheetah.xml", "gymnasium/ant.xml"]


def mujoco_sinks(path: str, qpos: np.ndarray, seconds: float) -> float:
    """The deepest penetration of MuJoCo's contacts between the floor and the rest over ``seconds`` from rest at
    ``qpos`` (its own options)."""
    import mujoco

    m = mujoco.MjModel.from_xml_path(path)
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    deepest = 0.0
    for _ in range(round(seconds / m.opt.timestep)):
        mujoco.mj_step(m, d)
        if d.ncon:
            deepest = max(deepest, float(-np.min(d.contact.dist[: d.ncon])))
    return deepest


@pytest.mark.parametrize("name", DROPPED)
def test_dropped_on_the_floor_it_lands_without_sinking_and_without_gaining_energy(name: str) -> None:
    path = str(zoo() / name)
    machine = gp.from_mjcf(path)
    q0, v0 = machine.initial_state()
    traj = gp.simulate(machine.model, q0, v0, 2.0, record=np.linspace(0.0, 2.0, 201))
    assert traj.success and traj.lane == "friction"
    floor = [i for i, c in enumerate(machine.contacts) if c.name.startswith("floor")]
    assert traj.gap[0, floor].min() > 0.01  # it starts above the floor
    deepest = float(-traj.gap[:, floor].min())
    scale = float(np.abs(traj.energy).max())
    rise = float(np.max(np.diff(traj.energy)))
    touched = [e for e in traj.events if e["kind"] == "closes"]
    speed = float(np.abs(traj.v[-1]).max())
    sinks = mujoco_sinks(path, q0, 2.0)
    print(
        f"\n{name}: lands at t = {touched[0]['t']:.4f} s, {len(traj.events)} events; deepest {deepest:.1e} m below "
        f"the floor; energy rises by at most {rise:.1e} J (of {scale:.3g}); at 2 s speed {speed:.1e}; MuJoCo's soft "
        f"contacts let it sink {sinks:.2e} m"
    )
    assert touched and deepest <= 1e-9
    assert rise <= 1e-9 * scale
    assert traj.energy[-1] < traj.energy[0] - 1e-3 * scale  # the landing is plastic: energy is lost


def test_the_friction_lane_refuses_what_it_does_not_take() -> None:
    machine = gp.from_mjcf(str(zoo() / "gymnasium/hopper.xml"))
    q0, v0 = machine.initial_state()
    with pytest.raises(gp.InputError, match="method='rk4' is not taken by the friction lane"):
        gp.simulate(machine.model, q0, v0, 0.1, method="rk4")


def test_verify_says_it_does_not_check_a_frictional_run() -> None:
    machine = gp.from_mjcf(str(zoo() / "gymnasium/hopper.xml"))
    q0, v0 = machine.initial_state()
    traj = gp.simulate(machine.model, q0, v0, 0.2)
    with pytest.raises(gp.InputError, match="gp.verify does not check frictional motions"):
        gp.verify(machine.model, traj)
