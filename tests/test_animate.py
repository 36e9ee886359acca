"""plot.animate: the mechanism moving, drawn from the scene's drawing, saved as a GIF (issue 21 item 3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp import cli
from gausspp.errors import GaussppError, InputError

pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")


def _frames(path: Path) -> int:
    with Image.open(path) as gif:
        return int(gif.n_frames)


def _run(scene: gp.scenes.Scene) -> object:
    if scene.name == "overhead-crane":  # a tangential servo: the servo route
        return gp.simulate_servo(scene.model, scene.q0, scene.v0, scene.t_end, record=np.linspace(0, scene.t_end, 61))
    return gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, record=np.linspace(0, scene.t_end, 61))


@pytest.mark.parametrize(
    ("name", "frames"), [("pendulum", 12), ("two-masses", 20), ("overhead-crane", 15), ("planar-chain", 8)]
)
def test_animate_writes_a_gif_with_one_frame_per_asked_frame(tmp_path: Path, name: str, frames: int) -> None:
    scene = gp.scenes.get(name)
    out = tmp_path / f"{name}.gif"
    gp.plot.animate(scene, _run(scene), out=out, frames=frames, fps=10, dpi=60)
    assert out.stat().st_size > 0
    assert _frames(out) == frames


def test_fewer_samples_than_frames_gives_one_frame_per_sample(tmp_path: Path) -> None:
    scene = gp.scenes.get("pendulum", t_end=0.5)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, record=np.linspace(0, 0.5, 6))
    out = tmp_path / "short.gif"
    gp.plot.animate(scene, traj, out=out, frames=40, dpi=60)
    assert _frames(out) == 6


def test_a_scene_or_model_without_a_drawing_is_refused(tmp_path: Path) -> None:
    scene = gp.scenes.get("skate")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.1)
    with pytest.raises(InputError, match="'skate' has no drawing"):
        gp.plot.animate(scene, traj, out=tmp_path / "x.gif")
    with pytest.raises(InputError, match="has no drawing.*a Model carries none"):
        gp.plot.animate(scene.model, traj)
    assert not (tmp_path / "x.gif").exists()


def test_a_file_that_is_neither_gif_nor_mp4_is_refused(tmp_path: Path) -> None:
    scene = gp.scenes.get("pendulum", t_end=0.2)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end)
    with pytest.raises(InputError, match=r"must end in \.gif or \.mp4"):
        gp.plot.animate(scene, traj, out=tmp_path / "x.png")
    with pytest.raises(InputError, match="frames must be a positive integer"):
        gp.plot.animate(scene, traj, frames=0)


def test_the_run_command_writes_an_animation(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "masses.gif"
    code = cli.main(["run", "two-masses", "--t-end", "0.5", "--samples", "30", "--animate", str(out), "--quiet"])
    assert code == 0
    assert _frames(out) == 31
    assert str(out) in capsys.readouterr().out


def test_the_run_command_refuses_a_scene_without_a_drawing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "skate.gif"
    code = cli.main(["run", "skate", "--t-end", "0.1", "--animate", str(out), "--quiet"])
    assert code == 1
    assert "no drawing" in capsys.readouterr().err
    assert not out.exists()


def test_without_matplotlib_the_project_error(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    scene = gp.scenes.get("pendulum")
    with pytest.raises(GaussppError, match=r"gausspp\[plots\]"):
        gp.plot.animate(scene, object())
