"""Figures a reader understands at a glance (issue 21): every scene names its coordinates with units, the
figure of ``gausspp run SCENE --out FIG.png`` carries them, and each figure's title names its scene and a unit."""

from __future__ import annotations

import re
import runpy
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import gausspp as gp
from gausspp import cli
from gausspp.naming import numbered, velocity_name

pytest.importorskip("matplotlib")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from gausspp import plot  # noqa: E402
from gausspp.studies.realizability_map import realizability_grid  # noqa: E402
from gausspp.studies.report import Row  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: A unit in parentheses, as the figures write them: "(s)", "(m)", "(rad/s)", "(N·m)", "(kg·m²)", "(1)", …
UNIT = re.compile(r"\((?:s|m|rad|N|J|kg|°|1)[^()]*\)|\b(?:kg|N|m|s|rad)\b")


@pytest.fixture(autouse=True)
def _close_figures() -> Iterator[None]:
    yield
    plt.close("all")


def texts(fig: Any) -> list[str]:
    """Every text a reader sees: the suptitle, each axes' title, axis labels and legend entries."""
    out = [fig._suptitle.get_text()] if fig._suptitle is not None else []
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        legend = ax.get_legend()
        out += [t.get_text() for t in legend.get_texts()] if legend is not None else []
    return [t for t in out if t]


def titles(fig: Any) -> str:
    """The suptitle and the axes' titles, one string."""
    head = [fig._suptitle.get_text()] if fig._suptitle is not None else []
    return "\n".join(head + [ax.get_title() for ax in fig.axes])


def assert_announces(fig: Any, scene: str) -> None:
    """The title names ``scene``; the title or an axis label states a unit."""
    assert scene in titles(fig), titles(fig)
    assert any(UNIT.search(t) for t in texts(fig)), texts(fig)


# -- the scenes' coordinates ---------------------------------------------------------------------------------------
def built(name: str) -> gp.scenes.Scene:
    short = {"t_end": 0.05} if "t_end" in gp.scenes.parameters(name) else {}
    try:
        return gp.scenes.get(name, **short)
    except gp.GaussppError as exc:  # the robots need an optional extra
        if name in gp.scenes.ROBOT and "pip install" in str(exc):
            pytest.skip(str(exc))
        raise


@pytest.mark.parametrize("name", gp.scenes.names())
def test_every_scene_names_its_coordinates_with_units(name: str) -> None:
    scene = built(name)
    assert scene.coordinates is not None and len(scene.coordinates) == scene.q0.size
    assert scene.velocity_names is not None and len(scene.velocity_names) == scene.v0.size
    for label in (*scene.coordinates, *scene.velocity_names):
        assert re.search(r" \([^()]+\)$", label), f"{name}: {label!r} has no unit"
    assert len(set(scene.coordinates)) == len(scene.coordinates), scene.coordinates


def test_velocity_names_are_the_coordinates_dotted() -> None:
    assert velocity_name("x₁ (m)") == "x\u0307₁ (m/s)"
    assert velocity_name("θ (rad)") == "θ\u0307 (rad/s)"
    assert velocity_name("elbow (rad)") == "d/dt elbow (rad/s)"
    assert numbered(["x (m)", "θ (rad)"], 2) == ("x₁ (m)", "θ₁ (rad)", "x₂ (m)", "θ₂ (rad)")
    rigid = gp.scenes.get("rigid-body-servo")
    assert rigid.velocity_names == ("ω₁ (rad/s)", "ω₂ (rad/s)", "ω₃ (rad/s)")  # not the quaternion's


# -- gausspp run --out FIG.png -----------------------------------------------------------------------------------
@pytest.fixture
def saved_figures(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """The figures saved while the test runs (the Figure objects, not the PNG)."""
    figures: list[Any] = []
    original = Figure.savefig

    def keep(self: Any, *args: Any, **kwargs: Any) -> Any:
        figures.append(self)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep)
    return figures


def test_run_out_png_labels_the_scene_coordinates(saved_figures: list[Any], tmp_path: Path) -> None:
    out = tmp_path / "fig.png"
    assert cli.main(["run", "two-masses", "--quiet", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and not (tmp_path / "two-masses.npz").exists()
    (fig,) = saved_figures
    seen = texts(fig)
    for label in (*gp.scenes.get("two-masses").coordinates, "x\u0307₁ (m/s)", "time t (s)"):  # type: ignore[misc]
        assert label in seen, seen
    assert "$q_{1}$" not in seen and "two-masses" in titles(fig)


def test_run_out_directory_labels_a_rigid_body(saved_figures: list[Any], tmp_path: Path) -> None:
    args = ["run", "rigid-body-servo", "--quiet", "--method", "rk4", "--dt", "0.01", "-p", "t_end=0.1"]
    assert cli.main([*args, "--out", str(tmp_path)]) == 0
    (fig,) = saved_figures
    assert {"q_w (1)", "ω₃ (rad/s)"} <= set(texts(fig))  # v is ω, not the quaternion's rate


def test_trajectory_names_label_q_and_v() -> None:
    scene = gp.scenes.get("crane", t_end=0.1)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.1, method="rk4", dt=0.01)
    seen = texts(plot.trajectory(traj, names=scene.coordinates))
    assert {"x (m)", "θ (rad)", "x\u0307 (m/s)", "θ\u0307 (rad/s)"} <= set(seen)
    explicit = texts(plot.trajectory(traj, names=scene.coordinates, q_labels=["a", "b"]))
    assert "a" in explicit and "θ (rad)" not in explicit  # q_labels win over names


# -- each changed figure names its scene and a unit ---------------------------------------------------------------
def test_realizability_map_title() -> None:
    fig = plot.realizability_map(realizability_grid((1.0, 2.0, 3.0), (1.0, 1.0, 1.0), resolution=6.0))
    assert_announces(fig, "rigid-body-servo")
    assert "kg·m²" in titles(fig)


def test_work_precision_title() -> None:
    rows = [
        Row("pendulum", "rk4", "direct", "s", e, e, 1.0, "exact", 0, 0, w, 1, 1, "success", "")
        for e, w in ((1e-4, 1e-3), (1e-8, 1e-2))
    ]
    fig = plot.work_precision(rows, "pendulum", title="m = 1 kg, L = 1 m")
    assert_announces(fig, "pendulum")
    assert "L = 1 m" in titles(fig) and "wall time (s)" in fig.axes[0].get_xlabel()


def test_verification_title() -> None:
    scene = gp.scenes.get("two-masses", k=3.0, v=0.5)
    traj = gp.simulate(
        scene.model, scene.q0, scene.v0, 1.0, method="DOP853", rtol=1e-11, atol=1e-13, record=np.linspace(0, 1, 81)
    )
    fig = plot.verification(gp.verify(scene.model, traj), traj, title="scene two-masses: m1 = 1 kg")
    assert_announces(fig, "two-masses")
    assert "time t (s)" in texts(fig)


def test_motion_figures_state_units() -> None:
    scene = gp.scenes.get("crane", t_end=0.1)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.1, method="rk4", dt=0.01)
    assert_announces(plot.reaction_over_time(traj, title="scene crane"), "crane")
    assert_announces(plot.trajectory(traj, names=scene.coordinates, title="scene crane"), "crane")


def test_contacts_energy_panel_states_units() -> None:
    scene = gp.scenes.get("bouncing-pendulum", t_end=0.8)
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.8, method="DOP853", rtol=1e-9, atol=1e-11)
    seen = texts(plot.contacts(scene.model, traj, title="scene bouncing-pendulum"))
    assert {"energy (J)", "time t (s)", "gap g (m)", "contact force (N)"} <= set(seen)


def example_figure(script: str, monkeypatch: pytest.MonkeyPatch, tmp_path: Path, *args: str) -> Any:
    """Run ``examples/script`` in this process and return the figure it saved."""
    figures: list[Any] = []
    original = Figure.savefig
    monkeypatch.setattr(Figure, "savefig", lambda self, *a, **k: (figures.append(self), original(self, *a, **k)))
    monkeypatch.setattr(sys, "argv", [script, str(tmp_path / "figure.png"), *args])
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(ROOT / "examples" / script), run_name="__main__")
    (fig,) = figures
    return fig


@pytest.mark.parametrize(
    "script, scene, args",
    [
        ("realizability_map.py", "rigid-body-servo", ()),
        ("verify_a_trajectory.py", "two-masses", ()),
        ("monte_carlo.py", "pendulum", ("--samples", "6", "--workers", "1")),
    ],
)
def test_example_figures_name_their_scene_and_units(
    script: str, scene: str, args: tuple[str, ...], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    fig = example_figure(script, monkeypatch, tmp_path, *args)
    assert_announces(fig, scene)


def test_skate_figure_states_scene_parameters_and_units() -> None:
    from gausspp.studies.figures import skate_runs, skate_title

    params = dict(v0=0.7, omega0=1.3, lam0=0.2, t_end=1.0)
    fig = gp.plot.skate(runs=skate_runs(samples=21, **params), title=skate_title(**params))
    assert_announces(fig, "skate")
    heading = titles(fig)
    assert "v0 = 0.7 m/s" in heading and "ω0 = 1.3 rad/s" in heading and "λ(0) = 0.2 kg·m/s" in heading
    assert "x (m)" in texts(fig) and "heading θ (rad)" in texts(fig)
