"""``from_mjcf`` (issue 31, item 4): MuJoCo MJCF models read by MuJoCo's parser and built as a spatial gp.Multibody.

Four models written here — an arm (three hinges on non-parallel axes, a slide, a static massive pedestal, a
massless body welded between two links, a massive tool without a joint), a free base with a hinged leg and a foot on
two perpendicular hinges (a universal), a spatial RSSR four-bar (hinge, ball, hinge, closed by a ``connect``), and a
massless jointed body carrying the bodies welded to it.
At random configurations the state mapped from MuJoCo's joint space satisfies every joint row, reproduces MuJoCo's
kinematics, and ``Jᵀ A J`` (``J``'s columns the mapped unit velocities: ``v`` is linear in ``qvel``) equals
MuJoCo's ``mj_fullM``; the loop runs 2 s in both, gausspp closed to 1e-10 m, MuJoCo's soft connect reported.
"""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.errors import BackendUnavailableError, GaussppError, InputError
from gausspp.multibody.mjcf import MJCFMachine, from_mjcf

needs_mujoco = pytest.mark.skipif(
    importlib.util.find_spec("mujoco") is None, reason="from_mjcf reads MJCF with MuJoCo: pip install mujoco"
)

TOL = 1e-12

ARM = """
<mujoco model="arm">
  <option gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="base" pos="0 0 0.1">
      <geom name="pedestal" type="cylinder" size="0.1 0.05"/>
      <body name="upper" pos="0 0 0.1" euler="0 0 30">
        <joint name="shoulder" type="hinge" axis="0 0 1" ref="0.2"/>
        <geom name="upper" type="capsule" fromto="0 0 0 0.5 0 0.1" size="0.04"/>
        <body name="mount" pos="0.5 0 0.1">
          <body name="fore" euler="10 0 0">
            <joint name="elbow" type="hinge" axis="0 1 0"/>
            <geom name="fore" type="box" size="0.2 0.03 0.02" pos="0.2 0 0"/>
            <body name="hand" pos="0.4 0 0">
              <joint name="wrist" type="hinge" axis="1 0 1" pos="0 0.01 0"/>
              <inertial pos="0.05 0.01 0" mass="0.3" diaginertia="0.001 0.002 0.0025" euler="10 20 30"/>
              <body name="slider" pos="0.1 0 0">
                <joint name="extend" type="slide" axis="1 0.2 0"/>
                <geom name="slider" type="box" size="0.05 0.02 0.02"/>
                <body name="tool" pos="0.08 0 0" euler="0 30 0">
                  <geom name="tool" type="ellipsoid" size="0.03 0.02 0.01" pos="0.02 0 0"/>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

FREE_BASE = """
<mujoco model="free-base">
  <option gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <body name="base" pos="0.1 0.2 1.0" euler="20 10 0">
      <freejoint name="root"/>
      <geom name="base" type="box" size="0.2 0.1 0.05"/>
      <body name="leg" pos="0.2 0 0">
        <joint name="hip" type="hinge" axis="0 1 0"/>
        <geom name="leg" type="capsule" fromto="0 0 0 0 0.05 -0.4" size="0.03"/>
        <body name="foot" pos="0 0.05 -0.4" euler="0 0 15">
          <joint name="ankle_x" type="hinge" axis="1 0 0"/>
          <joint name="ankle_y" type="hinge" axis="0 0.6 0.8"/>
          <geom name="foot" type="box" size="0.08 0.04 0.02" pos="0.03 0 -0.02"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

#: MuJoCo's stiffest connect at dt = 1e-4 (solref's time constant 2 dt, refsafe's floor; as benchmarks/peers.py)
RSSR = """
<mujoco model="rssr">
  <option timestep="1e-4" integrator="RK4" gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <body name="crank">
      <joint name="crank" type="hinge" axis="0 0 1"/>
      <geom name="crank" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
      <body name="coupler" pos="0.3 0 0">
        <joint name="ball" type="ball"/>
        <geom name="coupler" type="capsule" fromto="0 0 0 0.5 0 0.6" size="0.03"/>
      </body>
    </body>
    <body name="rocker" pos="0.8 0.5 0.3">
      <joint name="rocker" type="hinge" axis="1 0 0"/>
      <geom name="rocker" type="capsule" fromto="0 0 0 0 -0.5 0.3" size="0.03"/>
    </body>
  </worldbody>
  <equality>
    <connect name="loop" body1="coupler" body2="rocker" anchor="0.5 0 0.6"
             solref="2e-4 1" solimp="0.9999 0.9999 0.001 0.5 2"/>
  </equality>
</mujoco>
"""

#: a massless ``frame`` turned by ``yaw`` carries a box and a ball welded to it (MuJoCo compiles a massless body with
#: joints only so); a pendulum hangs from the massless, jointless ``ring`` on the box, and from it a box on three
#: hinges through one point (a ball joint)
CARRIED = """
<mujoco model="carried">
  <option gravity="0 0 -9.81"><flag contact="disable"/></option>
  <worldbody>
    <body name="frame" pos="0 0 1" euler="0 15 0">
      <joint name="yaw" type="hinge" axis="0 0 1" pos="0.05 0 0"/>
      <body name="weight" pos="0.2 0 -0.1" euler="30 0 0">
        <geom name="weight" type="box" size="0.1 0.05 0.02"/>
        <body name="ring" pos="0 0.1 0">
          <body name="pendulum" pos="0 0 -0.05">
            <joint name="swing" type="hinge" axis="1 0 0.3"/>
            <geom name="bob" type="capsule" fromto="0 0 0 0 0.05 -0.3" size="0.02"/>
            <body name="twirl" pos="0 0.05 -0.3" euler="0 20 0">
              <joint name="roll" type="hinge" axis="1 0 0"/>
              <joint name="pitch" type="hinge" axis="0 1 0"/>
              <joint name="yaw2" type="hinge" axis="0.3 0 1"/>
              <geom name="twirl" type="box" size="0.04 0.03 0.02" pos="0.03 0.01 -0.02"/>
            </body>
          </body>
        </body>
      </body>
      <body name="counter" pos="-0.2 0 0">
        <geom name="counter" type="ellipsoid" size="0.05 0.04 0.03"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

MODELS = {"arm": ARM, "free-base": FREE_BASE, "rssr": RSSR, "carried": CARRIED}


def _matrix(p: np.ndarray) -> np.ndarray:
    """The rotation of a unit quaternion ``(w, x, y, z)`` (written here, not gausspp's)."""
    w, x, y, z = p / np.linalg.norm(p)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _random_qpos(mujoco: Any, m: Any, rng: np.random.Generator) -> np.ndarray:
    """Hinges anywhere in (−π, π), slides within ±0.3 m, unit quaternions for ball and free joints."""
    T = mujoco.mjtJoint
    qpos = np.array(m.qpos0, float)
    for j in range(m.njnt):
        a, kind = int(m.jnt_qposadr[j]), m.jnt_type[j]
        if kind == T.mjJNT_HINGE:
            qpos[a] = rng.uniform(-np.pi, np.pi)
        elif kind == T.mjJNT_SLIDE:
            qpos[a] = rng.uniform(-0.3, 0.3)
        else:
            start = a + 3 if kind == T.mjJNT_FREE else a
            if kind == T.mjJNT_FREE:
                qpos[a : a + 3] = rng.normal(size=3)
            u = rng.normal(size=4)
            qpos[start : start + 4] = u / np.linalg.norm(u)
    return qpos


def _joint_rows(machine: MJCFMachine) -> tuple[ca.Function, ca.Function]:
    """``g(q)`` and its rate ``G(q) q̇(q, v)`` over the joint rows (the equalities' rows left out: a random
    configuration does not close a loop)."""
    mb = machine.multibody
    loops = {n for key, names in machine.rows.items() if key.startswith("equality ") for n in names}
    mech = mb.mechanism
    g = ca.vertcat(*[ca.SX(c.value(mech.q, mech.t)) for c in mb.constraints if c.name not in loops])
    rate = ca.jacobian(g, mech.q) @ mech.qdot
    return ca.Function("g", [mech.q, mech.t], [g]), ca.Function("rate", [mech.q, mech.v, mech.t], [rate])


def _full_mass_matrix(mujoco: Any, m: Any, d: Any) -> np.ndarray:
    M = np.zeros((m.nv, m.nv))
    try:
        mujoco.mj_fullM(m, d, M)  # MuJoCo ≥ 3.5 (4.0 here)
    except TypeError:
        mujoco.mj_fullM(m, M, d.qM)  # older MuJoCo
    return M


@needs_mujoco
@pytest.mark.parametrize("which", list(MODELS))
def test_the_mapped_state_keeps_every_joint_and_reproduces_mujocos_kinematics_and_mass_matrix(which: str) -> None:
    """20 random states per model: every joint row ``g(q) = 0`` to 1e-12 (measured ≤ 7.4e-16) and its rate
    (≤ 2.4e-15), the centres and principal axes MuJoCo's ``xipos``/``ximat`` to 1e-12 (0 and ≤ 8.9e-16), ``Jᵀ A J``
    MuJoCo's ``mj_fullM`` entrywise to 1e-12 relative to its largest entry (≤ 4.4e-16), and so the kinetic energies
    (≤ 8.6e-16 relative)."""
    import mujoco

    machine = from_mjcf(MODELS[which])
    m, model = machine.mujoco_model, machine.model
    g, rate = _joint_rows(machine)
    d = mujoco.MjData(m)
    rng = np.random.default_rng(31)
    worst = dict.fromkeys(["rows", "rates", "centres", "axes", "mass matrix", "energy"], 0.0)
    for _ in range(20):
        qpos, qvel = _random_qpos(mujoco, m, rng), rng.normal(size=m.nv)
        q, v = machine.state_from_mujoco(qpos, qvel)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        worst["rows"] = max(worst["rows"], float(np.abs(np.array(g(q, 0.0))).max()))
        worst["rates"] = max(worst["rates"], float(np.abs(np.array(rate(q, v, 0.0))).max()))
        for k, i in enumerate(machine.body_ids):
            worst["centres"] = max(worst["centres"], float(np.abs(q[7 * k : 7 * k + 3] - d.xipos[i]).max()))
            R = _matrix(q[7 * k + 3 : 7 * k + 7])
            worst["axes"] = max(worst["axes"], float(np.abs(R - d.ximat[i].reshape(3, 3)).max()))
            assert abs(np.linalg.norm(q[7 * k + 3 : 7 * k + 7]) - 1.0) <= TOL
        J = np.column_stack([machine.state_from_mujoco(qpos, e)[1] for e in np.eye(m.nv)])  # v = J qvel, exactly
        assert np.abs(J @ qvel - v).max() <= TOL * (1 + np.abs(v).max())
        A = np.asarray(model.step_data(0.0, q, v).A, float)
        M = _full_mass_matrix(mujoco, m, d)
        worst["mass matrix"] = max(worst["mass matrix"], float(np.abs(J.T @ A @ J - M).max() / np.abs(M).max()))
        T_mj = 0.5 * qvel @ M @ qvel
        worst["energy"] = max(worst["energy"], abs(0.5 * v @ A @ v - T_mj) / T_mj)
    print(f"\n{which}: " + ", ".join(f"{k} {x:.2g}" for k, x in worst.items()))
    assert max(worst.values()) <= TOL


@needs_mujoco
def test_a_wrong_axis_in_the_file_is_seen_by_the_rows_and_by_the_mass_matrix() -> None:
    """Negative controls: the arm's wrist axis tilted in the file moves MuJoCo's bodies off the rows built from the
    original file (by 1e-2, a million times the tolerance), and its elbow axis flipped changes MuJoCo's mass matrix
    away from the original ``Jᵀ A J`` (the hinge is the same line, so the rows alone cannot see a flip)."""
    import mujoco

    machine = from_mjcf(ARM)
    g, _rate = _joint_rows(machine)
    tilted = from_mjcf(ARM.replace('axis="1 0 1"', 'axis="1 0 0.9"'))
    flipped = from_mjcf(ARM.replace('axis="0 1 0"', 'axis="0 -1 0"'))
    rng = np.random.default_rng(7)
    qpos, qvel = _random_qpos(mujoco, machine.mujoco_model, rng), rng.normal(size=machine.mujoco_model.nv)
    q_tilted, _ = tilted.state_from_mujoco(qpos, qvel)
    off = float(np.abs(np.array(g(q_tilted, 0.0))).max())
    assert off > 1e6 * TOL
    q, v = machine.state_from_mujoco(qpos, qvel)
    J = np.column_stack([machine.state_from_mujoco(qpos, e)[1] for e in np.eye(len(qvel))])
    A = np.asarray(machine.model.step_data(0.0, q, v).A, float)
    d = mujoco.MjData(flipped.mujoco_model)
    d.qpos[:] = qpos
    mujoco.mj_forward(flipped.mujoco_model, d)
    M_flipped = _full_mass_matrix(mujoco, flipped.mujoco_model, d)
    differs = float(np.abs(J.T @ A @ J - M_flipped).max() / np.abs(M_flipped).max())
    print(f"\ntilted wrist: rows off by {off:.3g}; flipped elbow: mass matrix off by {differs:.3g} (relative)")
    assert differs > 1e6 * TOL


@needs_mujoco
def test_bodies_are_carried_as_the_docstring_says_and_a_file_reads_like_a_string(tmp_path: Path) -> None:
    """The static pedestal is ground, the massless ``mount`` rides on ``upper``, the jointless ``tool`` is welded
    (six rows), the two ankle hinges make one universal, the free base no row; the massless ``frame``'s hinge turns
    the box welded to it, and the ball welded to the frame is welded to the box; three hinges through one point are
    a ball joint; a massless moving body with nothing
    welded to it is MuJoCo's own error, passed on."""
    path = tmp_path / "arm.xml"
    path.write_text(ARM)
    arm = from_mjcf(path)
    assert arm.bodies == {
        "world": None, "base": None, "upper": "upper", "mount": "upper", "fore": "fore", "hand": "hand",
        "slider": "slider", "tool": "tool",
    }  # fmt: skip
    assert len(arm.rows["tool (no joint)"]) == 6 and arm.rows["extend"][0].startswith("prismatic extend")
    assert from_mjcf(str(path)).model.names == arm.model.names == from_mjcf(ARM).model.names
    free = from_mjcf(FREE_BASE)
    assert free.rows["root"] == () and len(free.rows["ankle_x+ankle_y"]) == 4
    assert free.rows["ankle_x+ankle_y"][-1] == "universal ankle_x+ankle_y [axes]"
    assert free.multibody.gravity.tolist() == [0.0, 0.0, -9.81]
    carried = from_mjcf(CARRIED)
    assert carried.bodies == {
        "world": None, "frame": "weight", "weight": "weight", "ring": "weight", "pendulum": "pendulum",
        "twirl": "twirl", "counter": "counter",
    }  # fmt: skip
    assert carried.rows["roll+pitch+yaw2"] == tuple(f"spherical roll+pitch+yaw2 [{a}]" for a in "xyz")
    assert carried.rows["yaw"][0] == "revolute yaw [x]" and "weight (no joint)" not in carried.rows
    assert len(carried.rows["counter (no joint)"]) == 6
    with pytest.raises(InputError, match="MuJoCo cannot read the XML string: .*mass and inertia of moving bodies"):
        from_mjcf(
            _pendulum(
                '<body name="gimbal"><joint name="spin"/><body><joint name="nod"/><geom size="0.1"/></body></body>'
            )
        )


@needs_mujoco
def test_the_spatial_four_bar_stays_closed_in_gausspp_beside_mujocos_soft_connect() -> None:
    """2 s of the RSSR four-bar from MuJoCo's ``qpos0`` (closed: MuJoCo computes the connect's second anchor there)
    and a ``qvel`` on the loop (the crank at 3 rad/s, least norm on the connect's Jacobian). gausspp at rtol = atol
    = 1e-12 keeps the loop closed to 1e-10 m (measured 8e-13) and its energy to 1e-9 (4.6e-12); MuJoCo (RK4, dt =
    1e-4, its stiffest connect) opens by 8.1e-9 m; the centres of mass of the two runs differ by 1.8e-7 m."""
    import mujoco

    machine = from_mjcf(RSSR)
    m, model = machine.mujoco_model, machine.model
    d = mujoco.MjData(m)
    coupler, rocker = m.body("coupler").id, m.body("rocker").id
    data = m.eq_data[m.equality("loop").id]

    def anchors() -> tuple[np.ndarray, np.ndarray]:  # mj_equalityAnchors of a body-semantic connect
        return (
            d.xpos[coupler] + d.xmat[coupler].reshape(3, 3) @ data[0:3],
            d.xpos[rocker] + d.xmat[rocker].reshape(3, 3) @ data[3:6],
        )

    d.qpos[:] = m.qpos0
    mujoco.mj_forward(m, d)
    p1, p2 = anchors()
    assert np.linalg.norm(p1 - p2) <= TOL
    jac1, jac2 = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    mujoco.mj_jac(m, d, jac1, None, p1, coupler)
    mujoco.mj_jac(m, d, jac2, None, p2, rocker)
    crank = np.eye(m.nv)[m.jnt_dofadr[m.joint("crank").id]]
    qvel = np.linalg.lstsq(np.vstack([jac1 - jac2, crank]), np.r_[0.0, 0.0, 0.0, 3.0], rcond=None)[0]
    q0, v0 = machine.state_from_mujoco(m.qpos0, qvel)
    rows = {c.name: c for c in machine.multibody.constraints}
    loop = [rows[n] for n in machine.rows["equality loop"]]

    def opening(q: np.ndarray) -> float:
        return float(np.linalg.norm([float(np.asarray(c.value(q, 0.0))) for c in loop]))

    assert opening(q0) <= TOL
    t_end, samples = 2.0, 201
    start = time.perf_counter()
    traj = gp.simulate(model, q0, v0, t_end, rtol=1e-12, atol=1e-12, record=np.linspace(0.0, t_end, samples))
    gp_seconds = time.perf_counter() - start
    assert traj.success
    gp_open = max(opening(q) for q in traj.q)
    energy = float(np.ptp(traj.energy) / np.abs(traj.energy).max())

    steps = round(t_end / m.opt.timestep)
    every = steps // (samples - 1)
    mujoco.mj_resetData(m, d)
    d.qpos[:], d.qvel[:] = m.qpos0, qvel
    mj_open, states = 0.0, [(d.qpos.copy(), d.qvel.copy())]
    start = time.perf_counter()
    for k in range(1, steps + 1):
        mujoco.mj_step(m, d)
        mujoco.mj_kinematics(m, d)  # mj_step leaves the positions' kinematics at t − dt
        p1, p2 = anchors()
        mj_open = max(mj_open, float(np.linalg.norm(p1 - p2)))
        if k % every == 0:
            states.append((d.qpos.copy(), d.qvel.copy()))
    mj_seconds = time.perf_counter() - start
    q_mj, v_mj = machine.state_from_mujoco(np.array([s[0] for s in states]), np.array([s[1] for s in states]))
    centres = np.r_[0:3, 7:10, 14:17]
    motion = float(np.abs(q_mj[:, centres] - traj.q[:, centres]).max())
    speeds = float(np.abs(v_mj - traj.v).max())
    turned = float(np.ptp([s[0][0] for s in states]))
    print(
        f"\nRSSR 2 s: gausspp loop opening {gp_open:.2g} m (energy {energy:.2g} rel., {gp_seconds:.2f} s); MuJoCo's "
        f"soft connect opens {mj_open:.2g} m ({mj_seconds:.2f} s, {steps} RK4 steps with per-step Python); centres "
        f"differ by {motion:.2g} m, velocities by {speeds:.2g}; the crank swings through {turned:.2f} rad"
    )
    assert gp_open <= 1e-10 and energy <= 1e-9 and turned > 1.0
    assert motion <= 1e-4  # the same machine: a mapping error would show at the scale of the links (0.1 m)


# ------------------------------------------------------------------------------------------------- refusals


def _pendulum(inside: str = "", joints: str = '<joint name="pivot" type="hinge" axis="0 1 0"/>', after: str = "",
              option: str = '<flag contact="disable"/>') -> str:  # fmt: skip
    return f"""
<mujoco model="pendulum">
  <option>{option}</option>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1" pos="0 0 -1"/>
    <site name="top" pos="0 0 0.2"/>
    <site name="side" pos="0.5 0 0"/>
    <body name="bob">
      {joints}
      <geom name="rod" type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02"/>
      <site name="end" pos="0 0 -0.5"/>
      {inside}
    </body>
  </worldbody>
  {after}
</mujoco>"""


_CHILD = '<body name="tip" pos="0 0 -0.5"><joint name="tip_hinge" axis="1 0 0"/><geom name="tip" size="0.05"/></body>'

REFUSED = {
    "tendon": (
        _pendulum(after='<tendon><spatial name="cable"><site site="top"/><site site="end"/></spatial></tendon>'),
        r"tendon\(s\) 'cable'",
    ),
    "joint equality": (
        _pendulum(_CHILD, after='<equality><joint name="couple" joint1="pivot" joint2="tip_hinge"/></equality>'),
        r"equality 'couple' is a joint equality: gausspp maps connect and weld only",
    ),
    "two hinges at two points": (
        _pendulum(joints='<joint name="h1" axis="1 0 0"/><joint name="h2" axis="0 1 0" pos="0 0 -0.1"/>'),
        r"body 'bob' has the joints 'h1' \(hinge\), 'h2' \(hinge\)",
    ),
    "hinges not perpendicular": (
        _pendulum(joints='<joint name="h1" axis="1 0 0"/><joint name="h2" axis="1 1 0"/>'),
        r"body 'bob' has the joints .*not perpendicular",
    ),
    "slide and hinge": (
        _pendulum(joints='<joint name="s" type="slide" axis="1 0 0"/><joint name="h" axis="0 1 0"/>'),
        r"body 'bob' has the joints 's' \(slide\), 'h' \(hinge\)",
    ),
    "actuator": (_pendulum(after='<actuator><motor name="drive" joint="pivot"/></actuator>'), r"actuator\(s\) 'drive'"),
    "contacts": (_pendulum(option=""), r"pair\(s\) of geoms could collide \('floor'–'rod'\)"),
    "limits": (
        _pendulum(joints='<joint name="pivot" axis="0 1 0" range="-1 1"/>'),
        r"limited joint\(s\) 'pivot'",
    ),
    "damping": (_pendulum(joints='<joint name="pivot" axis="0 1 0" damping="0.1"/>'), r"'pivot' have damping"),
    "armature": (_pendulum(joints='<joint name="pivot" axis="0 1 0" armature="0.1"/>'), r"'pivot' have armature"),
    "weld off its relpose": (
        _pendulum(after='<equality><weld name="hold" body1="bob" relpose="0 0 0.1 1 0 0 0"/></equality>'),
        r"equality 'hold' \(weld\) is not met at qpos0",
    ),
    "inactive equality": (
        _pendulum(after='<equality><connect name="pin" body1="bob" anchor="0 0 -0.5" active="false"/></equality>'),
        r"equality 'pin' is inactive",
    ),
}


@needs_mujoco
@pytest.mark.parametrize("case", list(REFUSED))
def test_what_cannot_be_mapped_is_refused_with_its_name(case: str) -> None:
    xml, match = REFUSED[case]
    with pytest.raises(InputError, match=match):
        from_mjcf(xml)


@needs_mujoco
def test_every_problem_is_listed_and_the_ignorable_ones_can_be_ignored() -> None:
    xml = _pendulum(
        joints='<joint name="pivot" axis="0 1 0" range="-1 1"/>',
        after='<actuator><motor name="drive" joint="pivot"/></actuator>'
        '<tendon><spatial name="cable"><site site="top"/><site site="end"/></spatial></tendon>',
        option="",
    )
    with pytest.raises(InputError) as caught:
        from_mjcf(xml)
    for word in ("actuator(s) 'drive'", "tendon(s) 'cable'", "limited joint(s) 'pivot'", "could collide"):
        assert word in str(caught.value)
    machine = from_mjcf(xml, actuators="ignore", tendons="ignore", contacts="ignore", limits="ignore")
    assert len(machine.rows["pivot"]) == 5
    with pytest.raises(InputError, match="actuators must be one of"):
        from_mjcf(xml, actuators="keep")


@needs_mujoco
def test_a_weld_and_a_site_connect_map_to_fixed_and_spherical_rows() -> None:
    """A weld left to MuJoCo's relpose (the pose of qpos0) holds the two bodies as at qpos0 (six rows, met there); a
    connect between sites that do not meet at qpos0 is a ball joint that :meth:`Multibody.assemble` closes."""
    weld = from_mjcf(_pendulum(_CHILD, after='<equality><weld name="hold" body1="tip" body2="bob"/></equality>'))
    q, _v = weld.state_from_mujoco(weld.mujoco_model.qpos0, np.zeros(weld.mujoco_model.nv))
    held = [c for c in weld.multibody.constraints if c.name in weld.rows["equality hold"]]
    assert len(held) == 6 and max(abs(float(np.asarray(c.value(q, 0.0)))) for c in held) <= TOL
    site = _pendulum(after='<equality><connect name="pin" site1="end" site2="side"/></equality>')
    pinned = from_mjcf(site)
    assert len(pinned.rows["equality pin"]) == 3
    q0, _ = pinned.multibody.assemble()
    ends = {c.name: float(np.asarray(c.value(q0, 0.0))) for c in pinned.multibody.constraints}
    assert max(abs(x) for x in ends.values()) <= 1e-12


HEAP = """
<mujoco model="heap">
  <worldbody>
    <geom name="ground" size="0.1"/>
    <body name="A"><freejoint/><geom name="a" size="0.1"/>
      <body name="B"><joint name="hb" axis="1 0 0"/><geom name="b" size="0.1"/>
        <body name="C"><joint name="hc" axis="0 1 0"/><geom name="c" size="0.1"/></body>
      </body>
      <body name="D"><geom name="d" size="0.1"/></body>
    </body>
    <body name="E"><freejoint/><geom name="e" size="0.1" contype="2" conaffinity="2"/></body>
    <body name="F"><freejoint/><geom name="f" size="0.1" contype="2" conaffinity="1"/></body>
    <body name="S"><geom name="s" size="0.1"/></body>
  </worldbody>
  <contact><exclude body1="A" body2="C"/><pair geom1="ground" geom2="s"/></contact>
</mujoco>"""


@needs_mujoco
def test_the_geoms_said_to_collide_are_those_mujoco_makes_collide() -> None:
    """Spheres all at one place, so that every pair MuJoCo's filters let through touches: the pairs from_mjcf names
    (weld, dof-less, parent, bitmask and exclude filters, explicit pairs) are exactly MuJoCo's contacts (17 of 36)."""
    import mujoco

    from gausspp.multibody.mjcf import _Builder

    m = mujoco.MjModel.from_xml_string(HEAP)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)

    def name(g: int) -> str:
        return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, int(g))

    touching = {frozenset((name(d.contact.geom1[k]), name(d.contact.geom2[k]))) for k in range(d.ncon)}
    said = {frozenset(pair) for pair in _Builder(mujoco, m, {}).collisions()}
    assert said == touching and len(said) == 17
    assert frozenset(("a", "c")) not in said and frozenset(("c", "d")) in said  # excluded A–C; D is not A
    with pytest.raises(InputError, match=r"17 pair\(s\) of geoms could collide"):
        from_mjcf(HEAP)


def test_without_mujoco_the_error_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco now raises ImportError
    with pytest.raises(BackendUnavailableError, match="pip install mujoco"):
        from_mjcf(ARM)


@needs_mujoco
def test_a_missing_file_and_malformed_xml_are_gausspp_errors(tmp_path: Path) -> None:
    missing = tmp_path / "nowhere.xml"
    with pytest.raises(InputError, match="no MJCF file") as caught:
        from_mjcf(missing)
    assert not isinstance(caught.value, FileNotFoundError) and isinstance(caught.value, GaussppError)
    with pytest.raises(InputError, match=r"MuJoCo cannot read the XML string: XML parse error.*MISMATCHED_ELEMENT"):
        from_mjcf("<mujoco><worldbody><body></worldbody></mujoco>")
    bad = tmp_path / "bad.xml"
    bad.write_text('<mujoco><worldbody><body><joint type="hinge" axis="0 0 0"/></body></worldbody></mujoco>')
    with pytest.raises(InputError, match=r"MuJoCo cannot read the file '.*bad.xml'"):
        from_mjcf(bad)
    with pytest.raises(InputError, match="source must be"):
        from_mjcf(3.0)
