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


def standing_ant(gx: float) -> tuple[gp.Model, np.ndarray, np.ndarray, float]:
    """Gymnasium's ant (a floating base: a free joint) standing on its four feet, each of its eight hinges held at
    its angle by a servo-constraint realized by that joint's torque (``gp.Force`` along the joint: ``D = Jᵀ``), with
    gravity tilted by ``gx`` along x — a steady horizontal push on every body, as a push at the centre of mass.
    Returns the model, the state (the feet on the floor, at rest) and the feet's friction coefficient."""
    import casadi as ca
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(zoo() / "gymnasium/ant.xml"))
    m.opt.gravity[0] = gx
    machine = gp.from_mjcf(m)
    q0, v0 = machine.initial_state()
    gaps = ca.Function("g", [machine.tree.q], [ca.vertcat(*[c.gap(machine.tree.q) for c in machine.contacts])])
    feet = [i for i, c in enumerate(machine.contacts) if c.name.startswith("floor–") and "ankle" in c.name]
    q0[2] -= float(np.min(np.array(gaps(q0)).ravel()[feet]))  # lowered onto its feet
    held = []
    for j in range(m.njnt):
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
            a, d = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            held.append(
                gp.Holonomic(
                    lambda q, t, a=a, c=float(q0[a]): q[a] - c,
                    name=f"hold {machine.joint_names[j]}",
                    realization=gp.Force(lambda q, v, t, d=d: ca.DM(np.eye(m.nv)[d][None, :])),
                )
            )
    model = gp.Model(machine.tree, held + list(machine.model.contacts), friction=machine.contacts)
    mu = {machine.contacts[i].mu for i in feet}
    assert len(mu) == 1
    return model, q0, v0, mu.pop()


def test_a_quadruped_holding_its_joints_stands_still_on_its_four_feet() -> None:
    """The ant on its four feet, joints held by their torques, gravity straight down: 1 s without moving
    (|v| ≤ 1e-9 m/s), its feet sticking; a push of 0.9 μ m g (gravity tilted) is held too."""
    for gx in (0.0, 9.0):
        model, q0, v0, mu = standing_ant(gx)
        assert gx < mu * 9.81
        traj = gp.simulate(model, q0, v0, 1.0, record=np.linspace(0.0, 1.0, 101))
        print(
            f"\npush {gx} m/s² (μ g = {mu * 9.81:.2f}): |v| ≤ {np.abs(traj.v).max():.1e}, modes {set(traj.modes[-1])}"
        )
        assert traj.success and np.abs(traj.v).max() <= 1e-9
        assert "stick" in traj.modes[-1] and "slide" not in traj.modes[-1]


def test_pushed_harder_than_its_feet_can_hold_the_quadruped_slides_as_coulomb_says() -> None:
    """A push of 12 m/s² (more than μ g = 9.81): the rigid ant slides on its four feet with the acceleration
    Coulomb's law gives its centre, ``a = g_x − μ g`` (the feet's normal forces add up to ``m g`` whatever their
    share), measured by a parabola through its base's path to 1e-8 relative. A control: at the push of 9 m/s² the
    same fit finds no motion."""
    model, q0, v0, mu = standing_ant(12.0)
    traj = gp.simulate(model, q0, v0, 1.0, record=np.linspace(0.0, 1.0, 101))
    assert traj.success
    accel = 2 * np.polyfit(traj.t, traj.q[:, 0], 2)[0]
    expected = 12.0 - mu * 9.81
    print(f"\nslides at {accel:.12f} m/s² (Coulomb: {expected:.12f})")
    assert abs(accel - expected) <= 1e-8 * expected
    assert np.abs(traj.q[:, 1]).max() <= 1e-9  # straight along the push
