"""The robot scenes (issue 20 item 3): ``ur5-tool-path`` and ``underactuated-arm``, their torques against Pinocchio.

Each scene simulates with its own solver (``scene.params["solver"]``: the QP for the redundant UR5, the direct
formula for the arm), and its servo torques along the motion are Pinocchio's inverse dynamics (RNEA) of that
motion to 1e-9 relative; the arm's realizability margin stays above 0.3 on its horizon. Without the robots extra,
building either scene is a project error naming it, and ``gausspp scenes`` still lists them.
"""

from __future__ import annotations

import warnings
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp.errors import GaussppError
from gausspp.scenes.underactuated_arm import three_link_urdf
from gausspp.scenes.ur5_tool_path import ur5_urdf


def test_robot_scenes_are_their_own_kind() -> None:
    robots = gp.scenes.names("robot")
    assert robots == ["ur5-tool-path", "underactuated-arm"]
    assert set(robots) <= set(gp.scenes.names())
    others = set(gp.scenes.names("equality")) | set(gp.scenes.names("general")) | set(gp.scenes.names("servo"))
    assert not set(robots) & others
    assert set(robots) <= set(gp.scenes.describe())  # listed without building (no extra needed)


@pytest.mark.parametrize("name", ["ur5-tool-path", "underactuated-arm"])
def test_without_the_extra_building_names_it(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    def missing(package: str) -> str:
        raise metadata.PackageNotFoundError(package)

    monkeypatch.setattr(metadata, "version", missing)
    monkeypatch.setattr(metadata, "distribution", missing)
    with pytest.raises(GaussppError, match=r"pip install 'gausspp\[robots\]'"):
        gp.scenes.get(name)


def _rnea_agrees(scene: gp.scenes.Scene, urdf: str, traj: gp.Trajectory) -> list[np.ndarray]:
    """Pinocchio's RNEA along ``traj``; each equals the scene's servo torques to 1e-9 relative."""
    pin = pytest.importorskip("pinocchio")
    pm = pin.buildModelFromUrdf(urdf)
    data = pm.createData()
    expected = []
    for q, v, a, tau in zip(traj.q, traj.v, traj.a, traj.reaction, strict=True):
        rnea = pin.rnea(pm, data, q, v, a)
        assert np.linalg.norm(tau - rnea) <= 1e-9 * np.linalg.norm(rnea)
        expected.append(rnea)
    return expected


def test_ur5_tool_path_torques_are_pinocchio_inverse_dynamics() -> None:
    pytest.importorskip("adam.casadi")
    pytest.importorskip("pinocchio")
    try:
        urdf = ur5_urdf()
    except GaussppError:
        pytest.skip("example-robot-data is not installed")
    scene = gp.scenes.get("ur5-tool-path")
    assert scene.params["solver"] == "qp" and scene.t_end == 1.2
    record = np.linspace(0.0, scene.t_end, 241)
    traj = gp.simulate(
        scene.model, scene.q0, scene.v0, scene.t_end, solver="qp", stabilize=scene.params["stabilize"], record=record
    )
    assert traj.status == "success"
    assert np.abs(traj.g).max() < 1e-8
    _rnea_agrees(scene, urdf, traj)
    assert traj.labels.coordinate == scene.model.mechanism.joint_names


def test_underactuated_arm_torques_are_pinocchio_inverse_dynamics(tmp_path: Path) -> None:
    pytest.importorskip("adam.casadi")
    pytest.importorskip("pinocchio")
    scene = gp.scenes.get("underactuated-arm")
    assert scene.params["solver"] == "direct" and scene.t_end == 0.5
    traj = gp.simulate(
        scene.model, scene.q0, scene.v0, scene.t_end, solver="direct", record=np.linspace(0.0, scene.t_end, 201)
    )
    assert traj.status == "success"
    assert np.abs(traj.g).max() < 1e-8
    urdf = tmp_path / "three.urdf"
    urdf.write_text(three_link_urdf())
    for rnea in _rnea_agrees(scene, str(urdf), traj):
        assert abs(rnea[1]) <= 1e-9 * np.linalg.norm(rnea)  # the elbow is passive
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.RealizabilityWarning)
        states = zip(traj.t, traj.q, traj.v, strict=True)
        margins = [scene.model.step(t, q, v, solver="direct").margin for t, q, v in states]
    assert min(margins) > 0.3


def test_robot_scene_parameters_are_checked() -> None:
    pytest.importorskip("adam.casadi")
    with pytest.raises(gp.ShapeError, match="'underactuated-arm': d must be 2 numbers"):
        gp.scenes.get("underactuated-arm", d=[0.1, 0.2, 0.3])
    scene = gp.scenes.get("underactuated-arm", d=[0.02, -0.01], t_end=0.3)
    assert scene.params["d"] == (0.02, -0.01) and scene.t_end == 0.3
