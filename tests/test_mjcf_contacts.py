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


# -- the finger: cylinders beside capsules, a spinner with dry friction ----------------------------------------------
FINGER_PAIRS = (
    "proximal_decoration–cap1",  # a hub (cylinder) against a capsule lying in the plane normal to its axis
    "proximal–spinner_decoration",
    "fingertip–spinner_decoration",
    "proximal_decoration–spinner_decoration",  # two parallel hubs
)


def test_the_fingers_cylinder_gaps_are_mujocos_distances() -> None:
    """At 100 random states of dm_control's finger, each cylinder pair's gap equals MuJoCo's ``mj_geomDistance`` (its
    convex collision, to its own tolerance); the cylinders that can never reach the floor are left out. (Where a
    capsule can reach a cylinder's flat end the pair is refused:
    :func:`test_a_capsule_that_can_reach_a_flat_end_is_refused`.)"""
    import mujoco

    finger = gp.from_mjcf(str(zoo() / "dm_control/finger.xml"))
    names = {c.name: c for c in finger.contacts}
    assert not [n for n in names if n.startswith("ground–") and "decoration" in n]
    m = finger.mujoco_model
    d = mujoco.MjData(m)
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(100):
        d.qpos[:] = m.qpos0 + rng.uniform(-2.0, 2.0, m.nq)
        mujoco.mj_forward(m, d)
        for pair in FINGER_PAIRS:
            ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in pair.split("–")]
            distance = mujoco.mj_geomDistance(m, d, ids[0], ids[1], 10.0, np.zeros(6))
            worst = max(worst, abs(float(names[pair].gap(d.qpos)) - distance))
    assert worst <= 1e-9


def test_the_spinners_dry_friction_stops_it_where_a_damper_alone_would_not() -> None:
    """The finger's spinner set turning at 3 rad/s, the finger out of its way: its damper (0.5) slows it
    exponentially, its ``frictionloss`` (0.1) stops it in finite time — an event "stops slipping" — and it stays
    still after (its velocity zero to round-off)."""
    finger = gp.from_mjcf(str(zoo() / "dm_control/finger.xml"))
    q0, v0 = finger.initial_state()
    v0[2] = 3.0
    run = gp.simulate(finger.model, q0, v0, 3.0)
    assert run.status == "success", run.message
    stops = [e for e in run.events if e.get("kind") == "stops slipping"]
    assert stops and abs(run.v[-1, 2]) <= 1e-12 * 3.0 and run.t[-1] > stops[0]["t"]
    # the closed form of I θ̈ = −c θ̇ − F from 3 rad/s: stops at t* = (I/c) ln(1 + c ω₀ / F)
    inertia = float(finger.mujoco_model.dof_armature[2]) + _spinner_inertia(finger)
    t_stop = inertia / 0.5 * np.log(1 + 0.5 * 3.0 / 0.1)
    assert abs(stops[0]["t"] - t_stop) <= 1e-6 * t_stop


def _spinner_inertia(finger: gp.MJCFMachine) -> float:
    """The spinner's moment of inertia about its hinge (MuJoCo's ``mj_fullM`` at the reference pose)."""
    import mujoco

    m = finger.mujoco_model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    return float(M[2, 2]) - float(m.dof_armature[2])


HUB = """
<mujoco>
  <option gravity="0 0 0"/>
  <worldbody>
    <geom name="hub" type="cylinder" size="0.1 0.05" pos="0 0 0" euler="{tilt}"/>
    <body name="arm" pos="0.3 0 0">
      <joint name="swing" type="hinge" axis="{axis}"/>
      <geom name="rod" type="capsule" fromto="0 0 0 -0.15 0 0" size="0.02"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_a_capsule_that_can_reach_a_flat_end_is_refused() -> None:
    """A rod swinging about the hub's axis stays beside its side: mapped, its gap MuJoCo's distance. The same rod
    swinging about an axis across the hub's may reach its flat end: refused by name (the control of the check)."""
    import mujoco

    beside = HUB.format(tilt="0 0 0", axis="0 0 1")
    machine = gp.from_mjcf(beside)
    (contact,) = machine.contacts
    m = mujoco.MjModel.from_xml_string(beside)
    d = mujoco.MjData(m)
    for angle in np.linspace(-1.0, 1.0, 9):
        d.qpos[0] = angle
        mujoco.mj_forward(m, d)
        distance = mujoco.mj_geomDistance(m, d, 0, 1, 10.0, np.zeros(6))
        assert abs(float(contact.gap(d.qpos)) - distance) <= 1e-9
    with pytest.raises(gp.InputError, match="cylinder–capsule.*end or rim"):
        gp.from_mjcf(HUB.format(tilt="0 0 0", axis="0 1 0"))
