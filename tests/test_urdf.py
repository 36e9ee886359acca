"""URDF front end (issue 20 item 2): ``gp.from_urdf`` against Pinocchio, and adam 0.5.0's bugs pinned down.

Three arms: the UR5 of example-robot-data (six revolute joints), and two written here — exactly two joints, and
a prismatic joint between two revolute ones — the cases adam-robotics 0.5.0 gets wrong. ``A(q)`` and the bias
forces ``h = −f`` equal Pinocchio's ``crba`` / ``nonLinearEffects``, and a frame's position, Jacobian and
acceleration Pinocchio's frame kinematics, to 1e-12 at random states.
"""

from __future__ import annotations

import subprocess
import sys
import warnings
from importlib import metadata
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

import gausspp as gp
from gausspp.errors import GaussppError, UnknownNameError
from gausspp.scenes.underactuated_arm import MOTORS, Q0, arm_model, link, three_link_urdf
from gausspp.scenes.ur5_tool_path import tool_path, ur5_urdf

pytest.importorskip("adam.casadi")
pin = pytest.importorskip("pinocchio")

TOL = 1e-12


def _joint(name: str, parent: str, child: str, kind: str = "revolute", axis: str = "0 1 0") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0.5 0.1 0.05" rpy="0.1 -0.2 0.3"/><axis xyz="{axis}"/>'
        '<limit effort="100" velocity="10" lower="-3" upper="3"/></joint>'
    )


def two_joint_urdf() -> str:
    """A planar-ish arm with exactly two revolute joints (adam: the joint Jacobian comes out 12 × 1)."""
    body = link("l1") + link("l2") + _joint("j1", "base", "l1", axis="0 0 1") + _joint("j2", "l1", "l2")
    return f'<robot name="two"><link name="base"/>{body}<link name="tip"/>' + _fixed("tip", "l2") + "</robot>"


def prismatic_urdf() -> str:
    """Revolute, prismatic (rotated origin), revolute (adam: a 12 × 1 motion subspace, a misplaced slider)."""
    body = link("l1") + link("l2") + link("l3")
    body += _joint("j1", "base", "l1", axis="0 0 1") + _joint("slide", "l1", "l2", "prismatic", "0.6 0 0.8")
    body += _joint("j3", "l2", "l3")
    return f'<robot name="slider"><link name="base"/>{body}<link name="tip"/>' + _fixed("tip", "l3") + "</robot>"


def _fixed(child: str, parent: str) -> str:
    return (
        f'<joint name="{child}_fixed" type="fixed"><parent link="{parent}"/><child link="{child}"/>'
        '<origin xyz="0.3 0 0" rpy="0 0 0"/></joint>'
    )


def ur5_path() -> Path:
    try:
        return Path(ur5_urdf())
    except GaussppError:
        pytest.skip("example-robot-data is not installed")


@pytest.fixture(params=["ur5", "two", "prismatic"])
def arm(request: pytest.FixtureRequest, tmp_path: Path) -> tuple[Path, str]:
    if request.param == "ur5":
        return ur5_path(), "tool0"
    path = tmp_path / f"{request.param}.urdf"
    path.write_text(two_joint_urdf() if request.param == "two" else prismatic_urdf())
    return path, "tip"


def _states(n: int, count: int = 4) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(20)
    return [(rng.uniform(-2, 2, n), rng.normal(size=n), rng.normal(size=n)) for _ in range(count)]


def test_mass_matrix_and_bias_forces_equal_pinocchio(arm: tuple[Path, str]) -> None:
    path, _ = arm
    mech = gp.from_urdf(str(path))
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    assert list(mech.joint_names) == [model.names[i] for i in range(1, model.njoints)]
    dynamics = ca.Function("dyn", [mech.q, mech.v], [mech.A, mech.f])
    for q, v, _ in _states(mech.nv):
        A, f = (np.array(x) for x in dynamics(q, v))
        M = pin.crba(model, data, q)
        np.testing.assert_allclose(A, np.triu(M) + np.triu(M, 1).T, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(-f.ravel(), pin.nonLinearEffects(model, data, q, v), rtol=TOL, atol=TOL)


def test_frame_kinematics_equal_pinocchio(arm: tuple[Path, str]) -> None:
    path, frame = arm
    mech = gp.from_urdf(str(path))
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    fid = model.getFrameId(frame)
    q_, v_ = ca.SX.sym("q_", mech.nq), ca.SX.sym("v_", mech.nv)  # a constraint's own symbols
    kin = ca.Function(
        "kin",
        [q_, v_],
        [
            gp.frame_position(mech, frame, q_),
            gp.frame_rotation(mech, frame, q_),
            gp.frame_jacobian(mech, frame, q_),
            gp.frame_acceleration_bias(mech, frame, q_, v_),
        ],
    )
    for q, v, a in _states(mech.nv):
        p, R, J, Jdv = (np.array(x) for x in kin(q, v))
        pin.forwardKinematics(model, data, q, v, a)
        pin.updateFramePlacements(model, data)
        pin.computeJointJacobians(model, data, q)
        np.testing.assert_allclose(p.ravel(), data.oMf[fid].translation, rtol=TOL, atol=TOL)
        np.testing.assert_allclose(R, data.oMf[fid].rotation, rtol=TOL, atol=TOL)
        Jp = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
        np.testing.assert_allclose(J, Jp, rtol=TOL, atol=TOL)
        acc = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED).linear
        np.testing.assert_allclose(J @ a + Jdv.ravel(), acc, rtol=TOL, atol=TOL)


def test_gravity_is_explicit(tmp_path: Path) -> None:
    """``g`` is gausspp's (9.81 by default, along −z), not adam's 9.80665."""
    path = tmp_path / "two.urdf"
    path.write_text(two_joint_urdf())
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    q = np.array([0.3, -0.7])
    for g in (9.81, 9.80665, 1.62):
        mech = gp.from_urdf(str(path), g=g)
        model.gravity.linear[:] = [0.0, 0.0, -g]
        f = np.array(ca.Function("f", [mech.q, mech.v], [mech.f])(q, np.zeros(2))).ravel()
        np.testing.assert_allclose(-f, pin.computeGeneralizedGravity(model, data, q), rtol=TOL, atol=TOL)


def test_energy_and_joint_selection(tmp_path: Path) -> None:
    """Energy ½vᵀAv + m g z_c; a chosen subset of joints keeps the others at zero."""
    path = tmp_path / "slider.urdf"
    path.write_text(prismatic_urdf())
    mech = gp.from_urdf(str(path), joints=["slide", "j1"])
    assert mech.joint_names == ("slide", "j1")
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    q, v = np.array([0.2, -0.4]), np.array([0.5, 1.5])
    full_q, full_v = np.array([-0.4, 0.2, 0.0]), np.array([1.5, 0.5, 0.0])  # pinocchio's order: j1, slide, j3
    energy = float(ca.Function("E", [mech.q, mech.v], [mech.energy])(q, v))
    kinetic = pin.computeKineticEnergy(model, data, full_q, full_v)
    potential = pin.computePotentialEnergy(model, data, full_q)
    assert energy == pytest.approx(kinetic + potential, rel=TOL, abs=TOL)


def test_errors_name_the_fix(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "two.urdf"
    path.write_text(two_joint_urdf())
    with pytest.raises(UnknownNameError, match="'elbow'.*known: \\['j1', 'j2'\\]"):
        gp.from_urdf(str(path), joints=["j1", "elbow"])
    mech = gp.from_urdf(str(path))
    with pytest.raises(UnknownNameError, match="'tool0'"):
        gp.frame_position(mech, "tool0")

    def missing(name: str) -> str:
        raise metadata.PackageNotFoundError(name)

    monkeypatch.setattr(metadata, "version", missing)
    with pytest.raises(GaussppError, match=r"pip install 'gausspp\[robots\]'"):
        gp.from_urdf(str(path))
    monkeypatch.setattr(metadata, "version", lambda name: "0.6.0")
    with pytest.raises(GaussppError, match="written for adam-robotics 0.5.0.*'0.6.0'"):
        gp.from_urdf(str(path))


def test_import_gausspp_does_not_import_adam() -> None:
    code = "import sys, gausspp; print(any(m == 'adam' or m.startswith('adam.') for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# -- adam-robotics 0.5.0's bugs, reproduced on adam's own classes (a failure here: upstream fixed one) ----------
def _plain_adam(path: Path, joints: list[str]) -> tuple[object, ca.SX]:
    from adam.casadi import KinDynComputations

    kd = KinDynComputations(str(path), joints, gravity=np.array([0.0, 0.0, -9.81, 0.0, 0.0, 0.0]))
    return kd, ca.SX.sym("s", len(joints))


def test_adam_bug_two_joints_jacobian(tmp_path: Path) -> None:
    """adam 0.5.0: ``CasadiLike.concatenate(..., axis=-1)`` stacks the two 6 × 1 joint columns into 12 × 1."""
    from gausspp.model.adam_robot import AdamRobot

    path = tmp_path / "two.urdf"
    path.write_text(two_joint_urdf())
    kd, s = _plain_adam(path, ["j1", "j2"])
    with pytest.raises(RuntimeError, match="Mismatching number of columns"):
        kd.jacobian("l2", ca.SX.eye(4), s)  # type: ignore[attr-defined]
    fixed = AdamRobot(str(path), ["j1", "j2"], 9.81)
    assert fixed.algorithms.joints_jacobian("l2", s).array.shape == (6, 2)
    assert fixed.algorithms.jacobian("l2", ca.SX.eye(4), s).array.shape == (6, 8)


def test_adam_bug_prismatic_motion_subspace(tmp_path: Path) -> None:
    """adam 0.5.0: a prismatic joint's motion subspace is 12 × 1, so the mass matrix fails to build."""
    path = tmp_path / "slider.urdf"
    path.write_text(prismatic_urdf())
    kd, s = _plain_adam(path, ["j1", "slide", "j3"])
    with pytest.raises(RuntimeError, match="incompatible dimensions"):
        kd.mass_matrix(ca.SX.eye(4), s)  # type: ignore[attr-defined]


def test_adam_bug_prismatic_placement(tmp_path: Path) -> None:
    """adam 0.5.0: a prismatic child sits at ``xyz + q·axis`` instead of ``xyz + R(rpy)·q·axis``."""
    path = tmp_path / "slider.urdf"
    path.write_text(prismatic_urdf())
    kd, s = _plain_adam(path, ["j1", "slide", "j3"])
    H = ca.Function("H", [s], [kd.forward_kinematics("l2", ca.SX.eye(4), s)])  # type: ignore[attr-defined]
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    q = np.array([0.0, 1.0, 0.0])
    pin.framesForwardKinematics(model, data, q)
    wrong = np.array(H(q))[:3, 3]
    right = data.oMf[model.getFrameId("l2")].translation
    assert np.linalg.norm(wrong - right) > 0.1
    mech = gp.from_urdf(str(path))
    ours = np.array(ca.Function("p", [mech.q], [gp.frame_position(mech, "l2")])(q)).ravel()
    np.testing.assert_allclose(ours, right, rtol=TOL, atol=TOL)


# -- item 3: servo inverse dynamics on the UR5 -------------------------------------------------------------------
def test_ur5_tool_path_by_joint_torques_is_pinocchio_inverse_dynamics() -> None:
    """The tool follows ``p(t)`` (3 coordinates) by the 6 joint torques: redundant, least compulsion (QP).

    The torques along the computed motion are Pinocchio's RNEA of that motion (1e-9 relative), and the
    integral principle accepts the motion.
    """
    path = str(ur5_path())
    mech = gp.from_urdf(path)
    q0 = np.array([0.1, -1.2, 1.5, -0.8, -1.4, 0.3])
    model = gp.Model(mech, tool_path(mech, "tool0", q0, np.array([0.08, 0.05, -0.04]), ca.DM.eye(6)))
    traj = gp.simulate(model, q0, np.zeros(6), 1.0, solver="qp", stabilize="baumgarte")
    _torques_are_pinocchios(path, model, traj)
    assert traj.labels.coordinate == mech.joint_names  # the URDF's joint names reach the results


def _torques_are_pinocchios(path: str, model: gp.Model, traj: gp.Trajectory) -> None:
    """The run kept its path, its joint torques are Pinocchio's inverse dynamics (RNEA) at every sample, and
    (23) accepts it as a motion."""
    assert traj.status == "success"
    assert np.abs(traj.g).max() < 1e-8
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    for q, v, a, tau in zip(traj.q, traj.v, traj.a, traj.reaction, strict=True):
        expected = pin.rnea(pm, data, q, v, a)
        assert np.linalg.norm(tau - expected) <= 1e-9 * np.linalg.norm(expected)
    assert gp.verify(model, traj).is_motion


def _servo_check(path: str, coords: list[int], q0: np.ndarray, solver: str) -> None:
    """The tip's ``coords`` follow ``p₀ + (1 − cos 2t) d`` by every joint's torque; RNEA and verify agree."""
    mech = gp.from_urdf(path)
    n = mech.nv
    d = np.array([0.06, -0.04, 0.05][: len(coords)])
    model = gp.Model(mech, tool_path(mech, "tip", q0, d, ca.DM.eye(n), coords))
    record = np.linspace(0.0, 1.0, 801)
    traj = gp.simulate(model, q0, np.zeros(n), 1.0, solver=solver, stabilize="baumgarte", record=record)
    _torques_are_pinocchios(path, model, traj)
    assert traj.labels.coordinate == mech.joint_names


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_two_joint_arm_tip_path_by_joint_torques_is_pinocchio_inverse_dynamics(tmp_path: Path, solver: str) -> None:
    """Two joints, two path coordinates (the tip's x and y): ``S = I₂`` square, one torque for the path."""
    path = tmp_path / "two.urdf"
    path.write_text(two_joint_urdf())
    _servo_check(str(path), [0, 1], np.array([0.4, 0.9]), solver)


@pytest.mark.parametrize("solver", ["direct", "qp"])
def test_prismatic_arm_tip_path_by_joint_forces_is_pinocchio_inverse_dynamics(tmp_path: Path, solver: str) -> None:
    """Revolute, prismatic, revolute: the tip's full position by two torques and the slider's force."""
    path = tmp_path / "slider.urdf"
    path.write_text(prismatic_urdf())
    _servo_check(str(path), [0, 1, 2], np.array([0.4, 0.3, 0.9]), solver)


# -- item 3: an underactuated arm (a passive elbow) ---------------------------------------------------------------
def _underactuated(tmp_path: Path) -> tuple[str, object, gp.Model]:
    path = tmp_path / "three.urdf"
    path.write_text(three_link_urdf())
    mech = gp.from_urdf(str(path))
    return str(path), mech, arm_model(mech)


Q_UNDER = np.array(Q0)


def _margin(model: gp.Model, t: float, q: np.ndarray, v: np.ndarray) -> float:
    """The realizability margin of the direct step at ``(t, q, v)`` (small margins are what is measured here)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.RealizabilityWarning)
        return model.step(t, q, v, solver="direct").margin


def test_underactuated_arm_follows_the_path_while_the_margin_holds(tmp_path: Path) -> None:
    """Two motors, a passive elbow, a tip path of 2 coordinates: ``J A⁻¹ D`` is 2 × 2, the direct formula.

    On [0, 0.5] s the margin stays near 0.4, the run succeeds, the torques are Pinocchio's RNEA with a zero
    elbow torque, and ``gp.verify`` accepts. Continued, the passive elbow is dragged towards a configuration
    where ``J A⁻¹ D`` is singular: the margin falls towards zero (a RealizabilityWarning) and the integration
    stops there (t ≈ 0.87 s).
    """
    path, _, model = _underactuated(tmp_path)
    traj = gp.simulate(model, Q_UNDER, np.zeros(3), 0.5, solver="direct", record=np.linspace(0.0, 0.5, 401))
    assert traj.status == "success"
    assert np.abs(traj.g).max() < 1e-8
    margins = [_margin(model, t, q, v) for t, q, v in zip(traj.t, traj.q, traj.v, strict=True)]
    assert min(margins) > 0.3
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    for q, v, a, tau in zip(traj.q, traj.v, traj.a, traj.reaction, strict=True):
        expected = pin.rnea(pm, data, q, v, a)
        assert abs(expected[1]) <= 1e-9 * np.linalg.norm(expected)  # the elbow is passive
        assert np.linalg.norm(tau - expected) <= 1e-9 * np.linalg.norm(expected)
    assert gp.verify(model, traj).is_motion

    with pytest.warns(gp.RealizabilityWarning, match="margin"):  # the recording sees the margin go
        longer = gp.simulate(model, Q_UNDER, np.zeros(3), 1.0, solver="direct", throw=False)
    assert longer.status != "success" and 0.5 < longer.t[-1] < 1.0
    assert _margin(model, longer.t[-1], longer.q[-1], longer.v[-1]) < 1e-4  # where it stopped: J A⁻¹ D singular


def test_underactuated_arm_singular_where_the_passive_joint_decouples(tmp_path: Path) -> None:
    """A configuration where ``det(J A⁻¹ D) = 0`` though ``J`` has full rank: the margin vanishes there."""
    _, mech, model = _underactuated(tmp_path)
    J = ca.jacobian(gp.frame_position(mech, "tip")[[0, 1]], mech.q)
    det = ca.Function("det", [mech.q], [ca.det(J @ ca.solve(mech.A, ca.DM(MOTORS).T))])
    q3 = brentq(lambda x: float(det([0.3, -0.3, x])), -1.5, -0.5, xtol=1e-15)
    singular = np.array([0.3, -0.3, q3])
    assert np.linalg.svd(np.array(ca.Function("J", [mech.q], [J])(singular)), compute_uv=False)[-1] > 0.1
    away = [_margin(model, 0.0, singular + [0, 0, eps], np.zeros(3)) for eps in (1e-2, 1e-4, 1e-6)]
    assert away[0] > away[1] > away[2] and away[2] < 1e-5  # → 0 as the state nears it
    try:
        at = _margin(model, 0.0, singular, np.zeros(3))
    except gp.RealizabilityError as exc:
        assert "tip path" in str(exc) and "margin" in str(exc)
    else:
        assert at < 1e-9
