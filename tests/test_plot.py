"""Figures of gausspp.plot (issue 6): each draws what it should and saves a PNG.

The acceptance line "the realizability-map figure shows the true zero set differing from
n ⟂ l for a non-principal l" is checked on the numbers behind the map.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.model.derived import gaps as contact_gaps

pytest.importorskip("matplotlib")
from gausspp import plot  # noqa: E402
from gausspp.studies.figures import skate_runs, suslov_steady, three_realizations_runs  # noqa: E402
from gausspp.studies.realizability_map import realizability_grid  # noqa: E402
from gausspp.studies.report import Row  # noqa: E402

PLOT_DIR = Path(plot.__file__).parent

INERTIA = (1.0, 2.0, 3.0)
SKEW_L = (1.0, 1.0, 1.0)


@pytest.fixture(autouse=True)
def _close_figures() -> Iterator[None]:
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


def saved(fig: Any, path: Path) -> Path:
    fig.savefig(path, dpi=60)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 1000
    return path


def tight(scene: gp.scenes.Scene, t_end: float, samples: int = 101) -> gp.Trajectory:
    return gp.simulate(
        scene.model,
        scene.q0,
        scene.v0,
        t_end,
        lam0=scene.lam0,
        method="DOP853",
        rtol=1e-12,
        atol=1e-14,
        record=np.linspace(0.0, t_end, samples),
    )


@pytest.fixture(scope="module")
def two_masses() -> dict[str, Any]:
    rod = gp.scenes.get("two-masses", realization="ideal", k=3.0, v=0.5)
    servo = gp.scenes.get("two-masses", realization="servo", k=3.0, v=0.5)
    return {"rod": rod, "servo": servo, "rod_path": tight(rod, 2.0, 201), "servo_path": tight(servo, 2.0, 201)}


def labelled(ax: Any) -> list[str]:
    return [line.get_label() for line in ax.get_lines() if not line.get_label().startswith("_")]


# -- trajectories ------------------------------------------------------------------------------------
def test_trajectory_one_run(two_masses: dict[str, Any], tmp_path: Path) -> None:
    fig = plot.trajectory(two_masses["rod_path"], title="rod")
    assert len(fig.axes) == 2
    q_ax, v_ax = fig.axes
    assert len(q_ax.get_lines()) == 2 and len(v_ax.get_lines()) == 2
    np.testing.assert_array_equal(q_ax.get_lines()[1].get_ydata(), two_masses["rod_path"].q[:, 1])
    assert fig.get_suptitle() == "rod"
    saved(fig, tmp_path / "trajectory.png")


def test_trajectory_several_runs_with_phase_portrait(two_masses: dict[str, Any], tmp_path: Path) -> None:
    runs = {"rod": two_masses["rod_path"], "servo": two_masses["servo_path"]}
    fig = plot.trajectory(runs, phase=True, q_labels=["x1", "x2"], v_labels=["v1", "v2"])
    assert len(fig.axes) == 3
    assert labelled(fig.axes[0]) == ["x1 (rod)", "x2 (rod)", "x1 (servo)", "x2 (servo)"]
    phase = fig.axes[2]
    assert len(labelled(phase)) == 4  # one curve per coordinate and run (start dots unlabelled)
    curve = phase.get_lines()[0]
    np.testing.assert_array_equal(curve.get_xdata(), runs["rod"].q[:, 0])
    np.testing.assert_array_equal(curve.get_ydata(), runs["rod"].v[:, 0])
    saved(fig, tmp_path / "phase.png")


def test_trajectory_bad_input() -> None:
    body = gp.scenes.get("rigid-body-servo")
    traj = tight(body, 0.5, 11)
    with pytest.raises(gp.InputError, match="nq == nv"):
        plot.trajectory(traj, phase=True)
    with pytest.raises(gp.ShapeError, match="labels"):
        plot.trajectory(traj, q_labels=["a"])
    with pytest.raises(gp.InputError, match="empty"):
        plot.trajectory({})


def test_reaction_over_time(two_masses: dict[str, Any], tmp_path: Path) -> None:
    fig = plot.reaction_over_time({"rod": two_masses["rod_path"], "servo": two_masses["servo_path"]})
    u_ax, z_ax, m_ax = fig.axes
    assert len(fig.axes) == 3
    assert labelled(u_ax) == ["rod (rod)", "rod (servo)"]  # the unknown named by its constraint (the model's name)
    np.testing.assert_array_equal(z_ax.get_lines()[0].get_ydata(), two_masses["rod_path"].compulsion)
    assert m_ax.get_yscale() == "log" and len(m_ax.get_lines()) == 3  # two margins and the warning level
    saved(fig, tmp_path / "reaction.png")


def test_reaction_over_time_flywheel_shows_the_state(tmp_path: Path) -> None:
    gyro = gp.scenes.get("gyrostat")
    fig = plot.reaction_over_time(tight(gyro, 1.0, 21))
    assert labelled(fig.axes[0]) == ["(ω, l) = 0", "state (ω, l) = 0"]  # u and λ named by their constraint
    saved(fig, tmp_path / "reaction_gyrostat.png")


# -- the realizability map (the acceptance line) --------------------------------------------------------
def test_map_true_zero_set_differs_from_the_naive_circle_for_a_skew_l() -> None:
    g = realizability_grid(INERTIA, SKEW_L, resolution=1.0)
    top = g.margin.max()
    assert top > 0.99  # n ∥ I l is an ideal-like direction: margin 1
    assert not g.principal
    # the margin vanishes on the true zero set (I⁻¹n, l) = 0 ...
    I = np.diag(INERTIA)
    assert np.abs(g.true_circle @ np.linalg.solve(I, g.l)).max() < 1e-12
    assert g.true_margin.max() <= 1e-2 * top
    # ... and not on most of the naive circle n ⟂ l
    assert np.abs(g.naive_circle @ g.l).max() < 1e-12
    assert np.median(g.naive_margin) >= 0.05
    assert np.mean(g.naive_margin > 1e-2 * top) > 0.9
    # the map's own grid says the same: cells near the true set are dark, near the naive circle mostly not
    near_true = np.abs(g.n @ g.pole) < 2e-3
    near_naive = (np.abs(g.n @ g.l) < 2e-3) & ~near_true
    assert near_true.sum() > 20 and near_naive.sum() > 20
    assert g.margin[near_true].max() <= 1e-2 * top
    assert np.median(g.margin[near_naive]) >= 0.05


def test_map_circles_coincide_for_a_principal_l() -> None:
    for l in [(0.0, 0.0, 1.0), (0.0, 2.0, 0.0)]:
        g = realizability_grid(INERTIA, l, resolution=2.0)
        assert g.principal
        assert abs(abs(g.pole @ g.l) - 1.0) < 1e-12
        assert g.true_margin.max() <= 1e-2 * g.margin.max()
        assert g.naive_margin.max() <= 1e-2 * g.margin.max()


def test_map_margin_is_the_library_margin(rng: np.random.Generator) -> None:
    """The vectorized margin behind the map equals gp.realizability.margin (A = I, J = lᵀ, D = n)."""
    I = np.array([[2.0, 0.3, -0.2], [0.3, 1.5, 0.1], [-0.2, 0.1, 1.0]])
    l = np.array([0.2, 1.0, -0.7])
    g = realizability_grid(I, l, resolution=5.0)
    for _ in range(20):
        i, j = rng.integers(g.lat.size), rng.integers(g.lon.size)
        n = g.n[i, j]
        expected = gp.realizability.margin(I, (l / np.linalg.norm(l))[None, :], n[:, None])
        assert g.margin[i, j] == pytest.approx(expected, abs=1e-12)
    assert g.true_margin.max() < 1e-12 and np.median(g.naive_margin) > 0.05


def test_realizability_map_figure(tmp_path: Path) -> None:
    fig = plot.realizability_map(realizability_grid(INERTIA, SKEW_L, resolution=2.0))
    assert len(fig.axes) == 2  # the map and its colour bar
    ax = fig.axes[0]
    kinds = {type(c).__name__ for c in ax.collections}
    assert "QuadMesh" in kinds and "QuadContourSet" in kinds
    contours = [c for c in ax.collections if type(c).__name__ == "QuadContourSet"]
    assert len(contours) == 2  # the true zero set and the naive circle
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("true zero set" in t for t in labels) and any("naive" in t for t in labels)
    assert "not zero" in ax.get_title()
    saved(fig, tmp_path / "map.png")
    grid = realizability_grid(INERTIA, (0, 0, 1), resolution=3.0)
    assert "principal" in plot.realizability_map(grid=grid).axes[0].get_title()


def test_realizability_grid_bad_input() -> None:
    with pytest.raises(gp.InputError, match="positive definite"):
        realizability_grid((1.0, -2.0, 3.0), SKEW_L)
    with pytest.raises(gp.ShapeError):
        realizability_grid(INERTIA, (1.0, 1.0))
    with pytest.raises(gp.InputError, match="resolution"):
        realizability_grid(INERTIA, SKEW_L, resolution=0.0)


# -- one constraint, three realizations; the skate --------------------------------------------------------
def test_three_realizations(tmp_path: Path) -> None:
    runs = three_realizations_runs(t_end=4.0, samples=201)
    assert set(runs) == {"ideal", "force", "inertial"}
    l = np.ones(3) / np.sqrt(3.0)
    I = np.diag(INERTIA)
    for traj in runs.values():
        np.testing.assert_allclose(traj.v[0], runs["ideal"].v[0])  # the same initial ω
        assert np.abs(traj.v @ l).max() < 1e-9  # the same constraint kept
    ends = np.array([traj.v[-1] for traj in runs.values()])
    assert min(np.linalg.norm(ends[i] - ends[j]) for i, j in [(0, 1), (0, 2), (1, 2)]) > 0.1  # three motions
    energy = {k: 0.5 * np.einsum("ti,ij,tj->t", tr.v, I, tr.v) for k, tr in runs.items()}
    assert np.ptp(energy["ideal"]) < 1e-8 and np.ptp(energy["force"]) > 0.1  # the ideal reaction does no work
    fig = plot.three_realizations(t_end=4.0, runs=runs, steady=suslov_steady())
    assert len(fig.axes) == 5
    for ax, key in zip(fig.axes[:3], ["ideal", "force", "inertial"], strict=True):
        assert len(ax.get_lines()) == 3  # ω₁, ω₂, ω₃
        np.testing.assert_array_equal(ax.get_lines()[0].get_ydata(), runs[key].v[:, 0])
        assert ax.get_title() == plot.THREE_LABELS[key]
    assert len(labelled(fig.axes[3])) == 5 and len(fig.axes[4].get_lines()) == 3
    saved(fig, tmp_path / "three.png")
    with pytest.raises(gp.InputError, match="keys"):
        plot.three_realizations(runs={"ideal": runs["ideal"]})


def test_skate(tmp_path: Path) -> None:
    runs = skate_runs(t_end=4.0, samples=201)
    non, vak = runs["nonholonomic"], runs["vakonomic"]
    assert np.hypot(non.q[:, 0], non.q[:, 1] - 1.0).max() == pytest.approx(1.0, abs=1e-8)  # circle of radius v0/ω0
    assert np.abs(non.q[:, :2] - vak.q[:, :2]).max() > 0.5  # another law, another path
    fig = plot.skate(runs=runs)
    plane, heading = fig.axes
    assert len(fig.axes) == 2
    assert labelled(plane) == ["nonholonomic (ideal)", "vakonomic", "start"]
    np.testing.assert_array_equal(plane.get_lines()[1].get_xdata(), vak.q[:, 0])
    assert len(heading.get_lines()) == 2
    saved(fig, tmp_path / "skate.png")


# -- verification ------------------------------------------------------------------------------------------
def test_verification_passing_and_failing(two_masses: dict[str, Any], tmp_path: Path) -> None:
    path = two_masses["rod_path"]
    good = gp.verify(two_masses["rod"].model, path)
    bad = gp.verify(two_masses["servo"].model, path)
    assert good.is_motion and not bad.is_motion
    fig = plot.verification({"rod model": good, "servo model": bad}, path)
    assert len(fig.axes) == 4  # δx and multipliers, one column per check
    top_good, top_bad = fig.axes[0], fig.axes[1]
    assert "a motion" in top_good.get_title() and "NOT" not in top_good.get_title()
    assert "NOT a motion" in top_bad.get_title() and f"{bad.relative_gap:.2e}" in top_bad.get_title()
    assert len(top_bad.get_lines()) == 2  # δx₁, δx₂
    np.testing.assert_array_equal(top_bad.get_lines()[1].get_ydata(), bad.delta_x[:, 1])
    assert np.abs(top_bad.get_lines()[0].get_ydata()).max() == 0.0  # the servo's virtual displacements: δx₁ = 0
    saved(fig, tmp_path / "verification.png")
    single = plot.verification(bad)
    assert len(single.axes) == 1 and "NOT a motion" in single.axes[0].get_title()
    saved(single, tmp_path / "verification_single.png")


# -- work-precision -------------------------------------------------------------------------------------------
def test_work_precision(tmp_path: Path) -> None:
    def row(method: str, solver: str, err: float, wall: float, status: str = "success") -> Row:
        return Row("demo", method, solver, "s", err, err, -np.log10(err), "exact", 0, 0, wall, 1, 1, status, "")

    rows = [
        row(m, s, e, w) for m in ("rk4", "DOP853") for s in ("direct", "qp") for e, w in ((1e-4, 1e-3), (1e-8, 1e-2))
    ]
    rows.append(row("Radau", "direct", float("nan"), float("nan"), "failed"))
    fig = plot.work_precision(rows, "demo")
    ax = fig.axes[0]
    assert len(ax.get_lines()) == 4 and ax.get_xscale() == "log" and "1 failed" in ax.get_title()
    saved(fig, tmp_path / "wp.png")
    assert [p.name for p in plot.save_work_precision(rows, tmp_path / "out")] == ["work_precision_demo.png"]


# -- contacts ------------------------------------------------------------------------------------------------
def markers(ax: Any, *gids: str) -> int:
    """Events marked on the gap panel: points of the marker lines with these gids."""
    return sum(len(line.get_xdata()) for line in ax.get_lines() if line.get_gid() in gids)


def recorded(model: gp.Model, traj: gp.Trajectory) -> gp.Trajectory:
    """``traj``, after checking that its recorded gaps are the model's gaps at each sample (``plot.contacts`` draws
    ``traj.gap`` and never evaluates the model)."""
    states = zip(traj.t, traj.q, traj.v, strict=True)
    expected = np.array([contact_gaps(model, t, q, v)[0] for t, q, v in states]).reshape(traj.t.size, -1)
    np.testing.assert_allclose(traj.gap, expected, rtol=0, atol=1e-12)
    return traj


@pytest.fixture(scope="module")
def rocking_block() -> tuple[gp.scenes.Scene, gp.Trajectory]:
    scene = gp.scenes.get("block-on-floor", tilt=0.3, e=0.5, drop=0.3, t_end=1.0)
    traj = gp.simulate(
        scene.model, scene.q0, scene.v0, 1.0, method="DOP853", rtol=1e-11, atol=1e-13, record=np.linspace(0, 1, 201)
    )
    return scene, recorded(scene.model, traj)


def test_contacts_rocking_block(rocking_block: tuple[gp.scenes.Scene, gp.Trajectory], tmp_path: Path) -> None:
    scene, traj = rocking_block
    names = scene.model.contact_row_names
    impacts = [ev for ev in traj.events if ev["kind"] == "impact"]
    plastic = [ev for ev in impacts if ev["plastic"]]
    assert len(impacts) > 20 and 0 < len(plastic) < len(impacts)  # rocks, then each corner comes to rest
    fig = plot.contacts(scene.model, traj, title="block")
    assert len(fig.axes) == 3
    gap_ax, force_ax, energy_ax = fig.axes
    assert labelled(gap_ax) == [f"gap of {n}" for n in names]
    # one force line per contact row, holding traj.contact_force
    assert labelled(force_ax) == [f"force on {n}" for n in names] and len(force_ax.get_lines()) == len(names)
    for i, line in enumerate(force_ax.get_lines()):
        np.testing.assert_array_equal(line.get_ydata(), traj.contact_force[:, i])
    # one marker per impact event, plastic ones apart, all on the floor g = 0
    assert markers(gap_ax, "impact", "plastic impact") == len(impacts)
    assert markers(gap_ax, "plastic impact") == len(plastic)
    assert markers(gap_ax, "lift-off", "touch") == 0
    assert all(np.all(line.get_ydata() == 0) for line in gap_ax.get_lines() if line.get_gid())
    # the gaps: the lower corner starts `drop` above the floor, both end on it
    lower = gap_ax.get_lines()[names.index("corner-")].get_ydata()
    assert lower[0] == pytest.approx(0.3) and np.all(np.asarray(lower) >= -1e-9)
    # energy: E, E + lost (constant: the resting forces do no work) and the lost energy (= −work of the reaction)
    energy, total, lost = energy_ax.get_lines()
    np.testing.assert_array_equal(energy.get_ydata(), traj.energy)
    assert np.ptp(total.get_ydata()) < 1e-9
    assert lost.get_ydata()[-1] == pytest.approx(traj.work_reaction[0] - traj.work_reaction[-1], rel=1e-9)
    assert lost.get_ydata()[-1] == pytest.approx(traj.energy[0] - traj.energy[-1], rel=1e-9)
    assert fig.get_suptitle() == "block"
    saved(fig, tmp_path / "contacts.png")


def test_contacts_lift_off_marked() -> None:
    """A ball on the floor pulled up by a growing force lets go (lift-off), flies and lands again."""
    ball = gp.Lagrangian(
        n=2,
        T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2),
        V=lambda q, t: 9.81 * q[1],
        F=lambda q, v, t: ca.vertcat(0.0, 20.0 * ca.sin(np.pi * t)),
    )
    model = gp.Model(ball, [gp.Unilateral(lambda q, t: q[1], name="floor", restitution=0.5)])
    traj = gp.simulate(model, [0.0, 0.0], [0.0, 0.0], 2.0, rtol=1e-10, atol=1e-12, record=np.linspace(0, 2, 101))
    traj = recorded(model, traj)
    kinds = [ev["kind"] for ev in traj.events]
    assert kinds[0] == "lift-off" and "impact" in kinds
    gap_ax, force_ax, _ = plot.contacts(model, traj).axes
    assert markers(gap_ax, "lift-off") == kinds.count("lift-off")
    assert markers(gap_ax, "impact", "plastic impact") == kinds.count("impact")
    assert len(force_ax.get_lines()) == 1 and force_ax.get_lines()[0].get_ydata()[0] == pytest.approx(9.81)


def test_contacts_bad_input(two_masses: dict[str, Any], rocking_block: tuple[gp.scenes.Scene, gp.Trajectory]) -> None:
    with pytest.raises(gp.InputError, match="no unilateral contacts"):
        plot.contacts(two_masses["rod"].model, two_masses["rod_path"])
    scene, traj = rocking_block
    with pytest.raises(gp.InputError, match=r"traj.contact_force has shape \(\d+, 1\), expected"):
        plot.contacts(scene.model, replace(traj, contact_force=traj.contact_force[:, :1]))
    ball = gp.Model(
        gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2)), [gp.Unilateral(lambda q, t: q[1])]
    )
    with pytest.raises(gp.InputError, match="traj.q has shape"):
        plot.contacts(ball, traj)  # the block's run is not the ball's


def test_contacts_draws_the_recorded_gaps(rocking_block: tuple[gp.scenes.Scene, gp.Trajectory]) -> None:
    """The gap panel holds ``traj.gap`` as recorded; without it, a clear error (the model is not evaluated)."""
    scene, traj = rocking_block
    gap_ax = plot.contacts(scene.model, traj).axes[0]
    for i, name in enumerate(scene.model.contact_row_names):
        line = next(line for line in gap_ax.get_lines() if line.get_label() == f"gap of {name}")
        np.testing.assert_array_equal(line.get_ydata(), traj.gap[:, i])
    no_gaps = type("OldRun", (), {f.name: getattr(traj, f.name) for f in fields(traj) if f.name != "gap"})()
    with pytest.raises(gp.InputError, match=r"carries no gaps \(traj.gap.*re-run"):
        plot.contacts(scene.model, no_gaps)
    with pytest.raises(gp.ShapeError, match=r"traj.gap has shape \(\d+, 1\), expected"):
        plot.contacts(scene.model, replace(traj, gap=traj.gap[:, :1]))


# -- plot draws, the studies compute -------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("name", "home"),
    [
        ("realizability_grid", "gausspp.studies.realizability_map"),
        ("servo_margin", "gausspp.studies.realizability_map"),
        ("three_realizations_runs", "gausspp.studies.figures"),
        ("skate_runs", "gausspp.studies.figures"),
    ],
)
def test_studies_live_in_studies_not_in_plot(name: str, home: str) -> None:
    """plot draws; the studies that compute its figures' numbers are not reachable from it."""
    import importlib

    assert callable(getattr(importlib.import_module(home), name))
    with pytest.raises(AttributeError):
        getattr(plot, name)


def test_figures_need_their_results() -> None:
    """A figure given no results says which study computes them, instead of computing them itself."""
    with pytest.raises(gp.InputError, match=r"grid is missing.*realizability_grid"):
        plot.realizability_map()
    with pytest.raises(gp.InputError, match="grid must be the result of"):
        plot.realizability_map(INERTIA)
    with pytest.raises(gp.InputError, match=r"runs is missing.*three_realizations_runs"):
        plot.three_realizations()
    with pytest.raises(gp.InputError, match=r"runs is missing.*skate_runs"):
        plot.skate()
    with pytest.raises(gp.InputError, match="runs must be the mapping"):
        plot.skate(runs=[1, 2])


def test_plot_imports_no_computation() -> None:
    """No module of gausspp.plot imports the model, the step, simulation, verification or the studies."""
    forbidden = ("gausspp.model", "gausspp.step", "gausspp.simulation", "gausspp.verification", "gausspp.studies")
    for path in sorted(PLOT_DIR.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                anchor = ["gausspp", "plot"][: 3 - node.level] if node.level else []
                base = ".".join([*anchor, node.module] if node.module else anchor)
                names = [base, *(f"{base}.{a.name}" for a in node.names)]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            bad = [n for n in names if n.startswith(forbidden)]
            assert not bad, f"{path.name} imports {bad}"


def test_two_masses_figure_announces_parameters_and_tells_motions_apart(tmp_path: Path) -> None:
    from gausspp.studies.demo import two_masses_figure

    fig = two_masses_figure()
    title = fig.get_suptitle()
    for part in ("two-masses", "k = 3 N/m", "v0 = 0.5 m/s", "kg", "rod", "servo"):
        assert part in title
    q_ax, v_ax, dq_ax, dv_ax = fig.axes
    rod, servo = q_ax.get_lines()[1], q_ax.get_lines()[3]  # x₂ of each run
    assert rod.get_linestyle() != servo.get_linestyle() and rod.get_marker() != servo.get_marker()
    assert np.abs(rod.get_ydata() - servo.get_ydata()).max() > 0.1  # the two motions differ visibly
    assert np.abs(dq_ax.get_lines()[1].get_ydata()).max() > 0.1  # and the difference panel shows it
    assert len(dv_ax.get_lines()) == 3  # Δv₁, Δv₂ and the zero line
    saved(fig, tmp_path / "two_masses.png")


def test_three_realizations_title_and_limits_show_the_motions() -> None:
    runs = three_realizations_runs(t_end=4.0, samples=201)
    fig = plot.three_realizations(t_end=4.0, runs=runs, steady=suslov_steady())
    title = fig.get_suptitle()
    for part in ("inertia I = diag(1, 2, 3) kg·m²", "l = (0.577, 0.577, 0.577)", "n = (0, 0, 1)", "rad/s", "t = 0…4 s"):
        assert part in title
    plane = fig.axes[3]
    fig.canvas.draw()
    paths = np.concatenate(
        [np.c_[line.get_xdata(), line.get_ydata()] for line in plane.get_lines()]
    )  # paths, ends, start, ω∞
    for lo_hi, data in ((plane.get_xlim(), paths[:, 0]), (plane.get_ylim(), paths[:, 1])):
        span = np.ptp(data)
        assert lo_hi[1] - lo_hi[0] < 1.3 * span  # the limits fit the paths: no empty band hides them
    styles = {(line.get_color(), line.get_linestyle()) for line in fig.axes[4].get_lines()}
    assert len(styles) == 3  # three energies told apart by colour and line style


def test_contacts_legend_does_not_contradict_the_restitution(
    rocking_block: tuple[gp.scenes.Scene, gp.Trajectory],
) -> None:
    scene, traj = rocking_block
    fig = plot.contacts(scene.model, traj, title=f"block-on-floor, e = {scene.params['e']}")
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert not any("e = 0" in t for t in texts)  # a plastic impact is a slow one, not a run with e = 0
    assert f"e = {scene.params['e']}" in fig.get_suptitle()


def test_a_figure_of_many_components_stays_readable(tmp_path: Path) -> None:
    """Issue 30, item 5: the 32-link chain's 96 coordinates — no legend of 96 entries over the axes but a colour
    scale from the first component to the last and a note naming them; every component its own colour. A few
    components keep the legend (the negative control)."""
    chain = gp.scenes.get("planar-chain", N=32)
    traj = gp.simulate(chain.model, chain.q0, chain.v0, 0.02)
    fig = plot.trajectory(traj, names=chain.coordinates, v_labels=chain.velocity_names)
    q_ax, v_ax = fig.axes[0], fig.axes[1]
    for ax in (q_ax, v_ax):
        assert ax.get_legend() is None
        assert any("96 curves" in t.get_text() for t in ax.texts)
    assert len({tuple(line.get_color()) for line in q_ax.get_lines()}) == 96
    assert sum(ax.get_label() == "<colorbar>" for ax in fig.axes) == 2
    fig.savefig(tmp_path / "chain.png")
    few = gp.scenes.get("planar-chain", N=2)
    small = plot.trajectory(gp.simulate(few.model, few.q0, few.v0, 0.02), names=few.coordinates)
    assert small.axes[0].get_legend() is not None and len(small.axes[0].get_legend().get_texts()) == 6
