"""example-robot-data's robots through ``gp.from_urdf`` (issue 43): every URDF that Pinocchio loads with
``nq == nv``, with its mass matrix and bias forces equal to Pinocchio's, quietly; floating bases against
Pinocchio's free-flyer; a floating robot falling freely.

The robots' files are URDF as their authors wrote them: joints and inertials without ``<origin>`` (URDF's identity
pose), materials with textures, transmissions, Gazebo tags. The references are Pinocchio's ``crba`` and ``rnea`` at
the same state, joints matched by name.
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import gausspp as gp

pytest.importorskip("adam.casadi")
pin = pytest.importorskip("pinocchio")

TOL = 1e-12


def robots_dir() -> Path | None:
    import importlib.util

    spec = importlib.util.find_spec("cmeel")
    for base in [Path(p) for p in spec.submodule_search_locations] if spec and spec.submodule_search_locations else []:
        candidate = base.parent / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if candidate.is_dir():
            return candidate
    import sys

    candidate = Path(sys.prefix) / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}"
    candidate = candidate / "site-packages" / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
    return candidate if candidate.is_dir() else None


ROOT = robots_dir()
FILES = sorted(str(p.relative_to(ROOT)) for p in ROOT.glob("**/*.urdf")) if ROOT else []


def pinocchio_model(path: str, floating: bool = False):  # noqa: ANN201
    try:
        return pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
    except Exception:  # Pinocchio's parser refuses the file (a robot without a name): not compared
        return None


def worst_difference(mech: gp.MassMatrix, model, floating: bool, states: int = 2, seed: int = 0) -> float:  # noqa: ANN001
    """The largest relative difference of ``A`` and ``h = −f`` from Pinocchio's ``crba``, ``rnea`` at random
    states (the joints matched by name; a floating base's quaternion ``(w, x, y, z)`` here, ``(x, y, z, w)`` there)."""
    first = 2 if floating else 1
    names = [model.names[i] for i in range(first, model.njoints)]
    perm = np.array([mech.joint_names.index(n) for n in names], dtype=int)
    fn = ca.Function("f", [mech.q, mech.v], [mech.A, mech.f])
    data = model.createData()
    rng = np.random.default_rng(seed)
    base = 6 if floating else 0
    worst = 0.0
    for _ in range(states):
        s, sdot = rng.uniform(-1, 1, len(names)), rng.normal(size=len(names))
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        p, u = rng.normal(size=3), rng.normal(size=6)
        q_pin = np.r_[p, quat[1:], quat[0], s] if floating else s
        v_pin = np.r_[u, sdot] if floating else sdot
        M = pin.crba(model, data, q_pin)
        M = np.triu(M) + np.triu(M, 1).T
        h = pin.rnea(model, data, q_pin, v_pin, np.zeros(model.nv))
        q, v = np.zeros(mech.nq), np.zeros(mech.nv)
        if floating:
            q[:7], v[:6] = np.r_[p, quat], u
        q[base + (1 if floating else 0) + perm], v[base + perm] = s, sdot
        A, f = fn(q, v)
        order = np.r_[np.arange(base), base + perm]
        A, minus_f = np.array(A)[np.ix_(order, order)], -np.array(f).ravel()[order]
        worst = max(worst, np.abs(A - M).max() / np.abs(M).max(), np.abs(minus_f - h).max() / max(1.0, np.abs(h).max()))
    return worst


def compared(name: str) -> bool:
    model = pinocchio_model(str(ROOT / name))
    return model is not None and model.nq == model.nv and model.nv > 0


@pytest.mark.skipif(ROOT is None, reason="example-robot-data is not installed (pip install 'gausspp[test]')")
@pytest.mark.parametrize("name", FILES)
def test_each_robot_pinocchio_loads_loads_with_its_dynamics_and_quietly(
    name: str, capfd: pytest.CaptureFixture
) -> None:
    path = str(ROOT / name)
    model = pinocchio_model(path)
    if model is None or model.nq != model.nv:
        pytest.skip("Pinocchio does not load it with nq == nv (continuous joints, or no robot name)")
    if model.nv == 0:
        with pytest.raises(gp.InputError, match="no revolute, continuous or prismatic joint"):
            gp.from_urdf(path)
        return
    capfd.readouterr()
    mech = gp.from_urdf(path)
    said = capfd.readouterr()
    assert said.out == "" and said.err == ""  # no "Unknown tag" chatter
    assert worst_difference(mech, model, floating=False) <= TOL


def test_the_whole_collection_is_compared() -> None:
    """The parametrized test above compares every file Pinocchio loads with nq == nv (59 of 69, two more with no
    joint refused by name); a file lost from the list would shrink the count."""
    if ROOT is None:
        pytest.skip("example-robot-data is not installed")
    assert len(FILES) == 69
    assert sum(compared(n) for n in FILES) == 59


@pytest.mark.parametrize("name", ["solo_description/robots/solo12.urdf", "talos_data/robots/talos_reduced.urdf"])
def test_a_floating_base_is_pinocchios_free_flyer(name: str) -> None:
    """solo12 (a quadruped) and TALOS (a humanoid, whose file has joints without ``<origin>``) with a floating base:
    ``A`` and the bias forces equal Pinocchio's free-flyer model to 1e-12 at random states; the same comparison with
    the base's quaternion read in Pinocchio's order ``(x, y, z, w)`` — a wrong convention — fails."""
    if ROOT is None:
        pytest.skip("example-robot-data is not installed")
    path = str(ROOT / name)
    mech = gp.from_urdf(path, floating=True)
    model = pinocchio_model(path, floating=True)
    assert mech.nq == model.nq + 0 and mech.nv == model.nv
    worst = worst_difference(mech, model, floating=True, states=3)
    print(f"\n{name}: floating base within {worst:.1e} of Pinocchio's free-flyer")
    assert worst <= TOL
    wrong = _quaternion_swapped(mech)
    assert worst_difference(wrong, model, floating=True, states=1) > 1e-6


class _Swapped:
    """``mech`` read with the base's quaternion in Pinocchio's order: the negative control."""

    def __init__(self, mech: gp.MassMatrix) -> None:
        q = mech.q
        swapped = ca.vertcat(q[0:3], q[6], q[3:6], q[7:])
        self.q, self.v, self.nq, self.nv = q, mech.v, mech.nq, mech.nv
        self.A = ca.substitute(mech.A, q, swapped)
        self.f = ca.substitute(mech.f, q, swapped)
        self.joint_names = mech.joint_names


def _quaternion_swapped(mech: gp.MassMatrix) -> _Swapped:
    return _Swapped(mech)


def test_a_floating_robot_falls_freely() -> None:
    """solo12 thrown with a spin and its joints turning: its centre of mass follows the parabola ``z₀ + ż₀t − gt²/2``
    to 1e-9 m over 0.5 s, its energy is kept to 1e-9 relative, its base's quaternion stays of unit length."""
    if ROOT is None:
        pytest.skip("example-robot-data is not installed")
    mech = gp.from_urdf(str(ROOT / "solo_description/robots/solo12.urdf"), floating=True)
    model = gp.Model(mech, [])
    rng = np.random.default_rng(4)
    q0 = np.r_[0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, rng.uniform(-0.5, 0.5, mech.nq - 7)]
    v0 = np.r_[0.3, -0.2, 1.5, 0.5, -1.0, 2.0, rng.uniform(-1.0, 1.0, mech.nv - 6)]
    traj = gp.simulate(model, q0, v0, 0.5, record=np.linspace(0.0, 0.5, 26))
    com = ca.Function("com", [mech.q], [mech.robot.com(mech.q)])
    vcom = ca.Function("vcom", [mech.q, mech.v], [ca.jtimes(mech.robot.com(mech.q), mech.q, mech.qdot)])
    c0, cdot0 = np.array(com(q0)).ravel(), np.array(vcom(q0, v0)).ravel()
    path = np.array([np.array(com(q)).ravel() for q in traj.q])
    expected = c0 + np.outer(traj.t, cdot0) + np.outer(traj.t**2, [0.0, 0.0, -0.5 * 9.81])
    off = float(np.abs(path - expected).max())
    energy = float(np.ptp(traj.energy) / np.abs(traj.energy).max())
    norm = float(np.abs(np.linalg.norm(traj.q[:, 3:7], axis=1) - 1.0).max())
    print(f"\nsolo12 falling: centre of mass off its parabola by {off:.1e} m, energy {energy:.1e}, |ρ| − 1 {norm:.1e}")
    assert traj.success and off <= 1e-9 and energy <= 1e-9 and norm <= 1e-12


def test_floating_takes_a_bool_and_a_jointless_robot_is_named(tmp_path: Path) -> None:
    if ROOT is None:
        pytest.skip("example-robot-data is not installed")
    with pytest.raises(gp.InputError, match="floating must be True or False"):
        gp.from_urdf(str(ROOT / "solo_description/robots/solo12.urdf"), floating="yes")
    with pytest.raises(gp.InputError, match="one rigid body"):
        gp.from_urdf(str(ROOT / "hector_description/robots/quadrotor_base.urdf"), floating=True)


def test_what_urdf_allows_reads_as_written_out(tmp_path: Path) -> None:
    """A joint and an inertial without ``<origin>``, a material with a texture, a transmission and a Gazebo tag:
    the same dynamics as the file with identity origins written out and those elements removed."""
    body = (
        '<link name="base"/><link name="arm"><inertial><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" '
        'iyy="0.2" iyz="0" izz="0.3"/></inertial><visual><geometry><box size="1 1 1"/></geometry><material '
        'name="m"><texture/></material></visual></link>'
        '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>'
        '<limit effort="1" velocity="1" lower="-1" upper="1"/></joint>'
    )
    extras = '<transmission name="t"><type>x</type></transmission><gazebo reference="arm"><mu1>1</mu1></gazebo>'
    loose, written = tmp_path / "loose.urdf", tmp_path / "written.urdf"
    loose.write_text(f'<robot name="r">{body}{extras}</robot>')
    written.write_text(
        '<robot name="r">'
        + body.replace("<inertial>", '<inertial><origin xyz="0 0 0" rpy="0 0 0"/>')
        .replace('<material name="m"><texture/></material>', "")
        .replace('<axis xyz="0 1 0"/>', '<origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>')
        + "</robot>"
    )
    a, b = gp.from_urdf(str(loose)), gp.from_urdf(str(written))
    fa = ca.Function("a", [a.q, a.v], [a.A, a.f])
    fb = ca.Function("b", [b.q, b.v], [b.A, b.f])
    for qa, qb in zip(fa(0.4, 1.3), fb(0.4, 1.3), strict=True):
        assert np.array_equal(np.array(qa), np.array(qb))


def test_a_floating_robots_feet_are_where_pinocchio_puts_them() -> None:
    """``gp.frame_position`` of solo12's four feet with a floating base: Pinocchio's frame placements to 1e-12 m at
    random states (where a contact point at a named frame is written)."""
    if ROOT is None:
        pytest.skip("example-robot-data is not installed")
    path = str(ROOT / "solo_description/robots/solo12.urdf")
    mech = gp.from_urdf(path, floating=True)
    model = pinocchio_model(path, floating=True)
    data = model.createData()
    feet = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
    where = ca.Function("feet", [mech.q], [ca.horzcat(*[gp.frame_position(mech, f) for f in feet])])
    names = [model.names[i] for i in range(2, model.njoints)]
    perm = np.array([mech.joint_names.index(n) for n in names], dtype=int)
    rng = np.random.default_rng(2)
    worst = 0.0
    for _ in range(5):
        s, quat, p = rng.uniform(-1, 1, len(names)), rng.normal(size=4), rng.normal(size=3)
        quat /= np.linalg.norm(quat)
        pin.framesForwardKinematics(model, data, np.r_[p, quat[1:], quat[0], s])
        q = np.r_[p, quat, np.zeros(len(names))]
        q[7 + perm] = s
        ours = np.array(where(q))
        theirs = np.column_stack([data.oMf[model.getFrameId(f)].translation for f in feet])
        worst = max(worst, float(np.abs(ours - theirs).max()))
    assert worst <= 1e-12


def test_adam_reads_a_joint_axis_as_written() -> None:
    """Pinned: adam-robotics 0.5.0 takes a joint's axis as written, so an axis of length 1.001 makes a mass matrix
    1.001² too large on that joint; gausspp makes it a direction first (as URDF means and Pinocchio reads it)."""
    from adam.model import Model as AdamModel

    from gausspp.model.adam_robot import FixedFactory, FixedMath

    body = (
        '<robot name="r"><link name="base"/><link name="arm"><inertial><origin xyz="0.5 0 0" rpy="0 0 0"/>'
        '<mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>'
        '<joint name="j" type="revolute"><origin xyz="0 0 0" rpy="0 0 0"/><parent link="base"/><child link="arm"/>'
        '<axis xyz="0 0 AXIS"/><limit effort="1" velocity="1" lower="-1" upper="1"/></joint></robot>'
    )
    from adam.core import RBDAlgorithms

    def adam_inertia(length: str) -> float:
        math = FixedMath()
        model = AdamModel.build(
            factory=FixedFactory(path=body.replace("AXIS", length), math=math), joints_name_list=["j"]
        )
        M, _ = RBDAlgorithms(model=model, math=math).crba(ca.SX.eye(4), ca.SX.zeros(1))
        return float(ca.evalf(M.array[6, 6]))

    assert adam_inertia("1.001") == pytest.approx(1.001**2 * adam_inertia("1"), rel=1e-12)
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "r.urdf"
        path.write_text(body.replace("AXIS", "1.001"))
        mech = gp.from_urdf(str(path))
        assert float(ca.evalf(ca.substitute(mech.A, mech.q, ca.DM([0.0])))) == pytest.approx(
            adam_inertia("1"), rel=1e-14
        )


def standing_solo12(mu: float = 0.8) -> tuple[gp.Model, np.ndarray]:
    """solo12 with a floating base on its four feet (``gp.frame_contact`` at ``FL_FOOT`` …, friction ``mu``), knees
    bent, each of its twelve joints held at its angle by a servo-constraint realized by that joint's torque."""
    mech = gp.from_urdf(str(ROOT / "solo_description/robots/solo12.urdf"), floating=True)
    feet = [gp.frame_contact(mech, f, mu=mu) for f in ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT")]
    s = np.zeros(len(mech.joint_names))
    for k, n in enumerate(mech.joint_names):
        front = 1.0 if n.startswith("F") else -1.0
        s[k] = 0.8 * front if "HFE" in n else (-1.6 * front if "KFE" in n else 0.0)
    q0 = np.r_[0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, s]
    gaps = ca.Function("g", [mech.q], [ca.vertcat(*[c.gap(mech.q) for c in feet])])
    q0[2] -= float(np.min(np.array(gaps(q0))))  # on its feet
    held = [
        gp.Holonomic(
            lambda q, t, a=7 + k, c=float(q0[7 + k]): q[a] - c,
            name=f"hold {n}",
            realization=gp.Force(lambda q, v, t, d=6 + k: ca.DM(np.eye(mech.nv)[d][None, :])),
        )
        for k, n in enumerate(mech.joint_names)
    ]
    return gp.Model(mech, held, friction=feet), q0


@pytest.mark.skipif(ROOT is None, reason="example-robot-data is not installed")
def test_solo12_stands_still_on_its_four_feet_and_slides_to_rest_as_coulomb_says() -> None:
    """solo12 standing on its feet with its joints held by their torques: 1 s without moving (|v| ≤ 1e-9), its feet
    sticking. Pushed to 0.2 m/s along x, it slides on its four feet and stops after ``v₀/(μg)`` at ``v₀²/(2μg)`` —
    Coulomb's law for its centre, whatever the feet's share of the weight — to 1e-8."""
    model, q0 = standing_solo12(mu=0.8)
    still = gp.simulate(model, q0, np.zeros(model.nv), 1.0, record=np.linspace(0.0, 1.0, 101))
    print(f"\nsolo12 standing: |v| ≤ {np.abs(still.v).max():.1e}, feet {still.modes[-1][:4]}")
    assert still.success and np.abs(still.v).max() <= 1e-9 and still.modes[-1][:4] == ("stick",) * 4
    v0 = np.zeros(model.nv)
    v0[0] = 0.2
    slid = gp.simulate(model, q0, v0, 0.05)
    stop = next(e for e in slid.events if e["kind"] == "stops slipping")
    t_stop, x_stop = 0.2 / (0.8 * 9.81), 0.2**2 / (2 * 0.8 * 9.81)
    print(
        f"solo12 pushed: stops at {stop['t']:.10f} s (Coulomb {t_stop:.10f}), at {slid.q[-1, 0]:.10f} m ({x_stop:.10f})"
    )
    assert slid.success and abs(stop["t"] - t_stop) <= 1e-8 * t_stop and abs(slid.q[-1, 0] - x_stop) <= 1e-8 * x_stop
