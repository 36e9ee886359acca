"""plot.animate: the mechanism moving, drawn from the scene's drawing, saved as a GIF (issue 21 item 3)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp import cli
from gausspp.errors import GaussppError, InputError

pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")


def _frames(path: Path) -> int:
    with Image.open(path) as gif:
        return int(gif.n_frames)


def _run(scene: gp.scenes.Scene) -> object:
    if scene.name == "overhead-crane":  # a tangential servo: index reduction
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
    scene = gp.scenes.get("crane")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.1)
    with pytest.raises(InputError, match="'crane' has no drawing"):
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
    out = tmp_path / "crane.gif"
    code = cli.main(["run", "crane", "--t-end", "0.1", "--animate", str(out), "--quiet"])
    assert code == 1
    assert "no drawing" in capsys.readouterr().err
    assert not out.exists()


def test_without_matplotlib_the_project_error(monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    scene = gp.scenes.get("pendulum")
    with pytest.raises(GaussppError, match=r"gausspp\[plots\]"):
        gp.plot.animate(scene, object())


def _sim(scene: gp.scenes.Scene, samples: int = 61) -> gp.Trajectory:
    times = np.linspace(0.0, scene.t_end, samples)
    return gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, lam0=scene.lam0, record=times)


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("skate", {"t_end": 2.0}),
        ("block-on-floor", {"tilt": 0.3, "drop": 0.1, "t_end": 0.6}),
        ("four-bar-redundant", {"t_end": 0.5}),
        ("gyrostat", {"t_end": 2.0}),
    ],
)
def test_the_new_drawings_animate_with_one_frame_per_asked_frame(tmp_path: Path, name: str, params: dict) -> None:
    scene = gp.scenes.get(name, **params)
    out = tmp_path / f"{name}.gif"
    gp.plot.animate(scene, _sim(scene), out=out, frames=9, fps=10, dpi=50)
    assert _frames(out) == 9


def test_runs_side_by_side_share_frames_limits_and_one_arrow_scale(tmp_path: Path) -> None:
    runs = {}
    for realization in ("ideal", "servo"):
        scene = gp.scenes.get("two-masses", realization=realization, t_end=1.0)
        runs[realization] = _sim(scene, samples=41 if realization == "ideal" else 57)  # different sample grids
    anim = gp.plot.animate(scene, runs, frames=11, fps=10)
    fig = anim._fig
    assert len(fig.axes) == 2
    assert fig.axes[0].get_xlim() == fig.axes[1].get_xlim()
    titles = [ax.get_title() for ax in fig.axes]
    assert titles[0].startswith("ideal: t = ") and titles[1].startswith("servo: t = ")
    out = tmp_path / "pair.gif"
    gp.plot.animate(scene, runs, frames=11, fps=10, dpi=50, out=out)
    assert _frames(out) == 11


def test_frames_are_spread_in_time_even_where_a_run_has_extra_samples() -> None:
    from gausspp.plot.animation import frame_samples

    t_events = np.sort(np.concatenate([np.linspace(0.0, 1.0, 101), 0.5 + 1e-4 * np.arange(1, 50)]))
    (idx,) = frame_samples([t_events], 11, 10)
    assert np.allclose(t_events[idx], np.linspace(0.0, 1.0, 11), atol=0.005)
    assert len(set(idx.tolist())) == 11


@given(
    t=st.lists(st.floats(0.0, 10.0, allow_nan=False), min_size=1, max_size=40, unique=True).map(sorted),
    grid=st.lists(st.floats(-1.0, 11.0, allow_nan=False), min_size=1, max_size=20),
)
@settings(max_examples=200, deadline=None)
def test_nearest_sample_agrees_with_a_brute_force_search(t: list[float], grid: list[float]) -> None:
    from gausspp.plot.animation import nearest

    ts, gs = np.array(t), np.array(grid)
    found = nearest(ts, gs)
    best = np.abs(ts[None, :] - gs[:, None]).min(axis=1)
    assert np.allclose(np.abs(ts[found] - gs), best, rtol=0.0, atol=1e-12 * (1.0 + np.abs(gs)))


def test_body_axes_are_the_rotated_basis_seen_from_the_view() -> None:
    from gausspp.scenes.rigid import VIEW_FROM, body_axes_drawing

    back = np.array(VIEW_FROM) / np.linalg.norm(VIEW_FROM)
    right = np.cross(-back, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -back)

    def seen(p: np.ndarray) -> np.ndarray:
        return np.array([right @ p, up @ p])

    quarter_turn_z = np.array([np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)])  # e₁ → y, e₂ → −x, e₃ → z
    tips = [np.asarray(seg[1]) for seg in body_axes_drawing(quarter_turn_z)["axes"]]
    expected = [seen(np.array(v, float)) for v in ((0, 1, 0), (-1, 0, 0), (0, 0, 1))]
    for tip, want in zip(tips, expected, strict=True):
        assert np.allclose(tip, want, atol=1e-12)
    # a wrong turn (the inverse rotation) is told apart
    inverse = [np.asarray(s[1]) for s in body_axes_drawing(quarter_turn_z * [1, -1, -1, -1])["axes"]]
    assert not np.allclose(inverse[0], expected[0], atol=1e-3)


def test_the_fast_gif_frames_match_full_renders_of_the_same_frames(tmp_path: Path) -> None:
    scene = gp.scenes.get("four-bar-redundant", t_end=0.5)
    traj = _sim(scene)
    out = tmp_path / "fourbar.gif"
    gp.plot.animate(scene, traj, out=out, frames=6, fps=10, dpi=60)
    anim = gp.plot.animate(scene, traj, frames=6, fps=10)
    fig = anim._fig
    fig.set_dpi(60)
    full = []
    for k in range(6):
        anim._func(k)
        fig.canvas.draw()
        full.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float))
    with Image.open(out) as gif:
        for k in (2, 5):
            gif.seek(k)
            frame = np.asarray(gif.convert("RGB"), float)
            assert frame.shape == full[k].shape
            same = np.abs(frame - full[k]).mean()
            other = np.abs(frame - full[k - 2]).mean()  # a neighbouring frame: the mechanism has moved
            assert same < 0.1 * other, (k, same, other)  # quantized to 64 colours: close, not equal


def test_the_scenes_the_readme_says_can_animate_have_drawings() -> None:
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    start = text.index("--animate out.gif` does the same")
    sentence = text[start : text.index("\n\n", start)]
    named = [name for name in re.findall(r"`([a-z0-9-]+)`", sentence) if name in gp.scenes.names()]
    assert len(named) >= 7
    for name in named:
        assert gp.scenes.get(name).drawing is not None, name
    for name in ("rigid-body-servo", "gyrostat", "gyrostat-extended"):  # "and the rigid bodies"
        assert gp.scenes.get(name).drawing is not None, name


def test_a_run_with_a_wrong_shape_or_a_nan_is_refused_clearly() -> None:
    from types import SimpleNamespace

    from gausspp.errors import ShapeError

    scene = gp.scenes.get("pendulum", t_end=0.2)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, record=np.linspace(0, 0.2, 11))
    with pytest.raises(ShapeError, match=r"run 'bad' needs t \(N,\) and q \(N, nq\)"):
        gp.plot.animate(scene, {"good": traj, "bad": SimpleNamespace(t=traj.t, q=traj.q[:-1])})
    q = traj.q.copy()
    q[:, :] = np.nan
    with pytest.raises(ShapeError, match="no finite point"):
        gp.plot.animate(scene, SimpleNamespace(t=traj.t, q=q))
    with pytest.raises(InputError, match="empty"):
        gp.plot.animate(scene, {})
