"""Labelled results (issue 20 item 4): names from the model, xarray / pandas views, save → load → verify."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp import cli
from gausspp.simulation.labels import Labels

pytest.importorskip("xarray")
pytest.importorskip("pandas")


@pytest.fixture(scope="module")
def pendulum() -> tuple[gp.Model, gp.Trajectory]:
    scene = gp.scenes.get("pendulum")
    return scene.model, gp.simulate(scene.model, scene.q0, scene.v0, 1.0)


@pytest.fixture(scope="module")
def block() -> tuple[gp.Model, gp.Trajectory]:
    scene = gp.scenes.get("block-on-floor")
    return scene.model, gp.simulate(scene.model, scene.q0, scene.v0, 1.0, dt=0.05)


class NamedCart(gp.Lagrangian):
    """A cart ``x`` with a pendulum ``phi`` (a mechanism that names its coordinates)."""

    coordinate_names = ("x", "phi")

    def __init__(self) -> None:
        super().__init__(
            2,
            T=lambda q, v, t: v[0] ** 2 + 0.5 * v[1] ** 2 + ca.cos(q[1]) * v[0] * v[1],
            V=lambda q, t: -9.81 * ca.cos(q[1]),
        )


def test_names_come_from_the_model(pendulum: tuple[gp.Model, gp.Trajectory]) -> None:
    model, traj = pendulum
    assert traj.labels.row == tuple(model.row_names) and len(traj.labels.unknown) == model.m
    assert traj.labels.coordinate == ()  # the pendulum's mechanism names none
    full = traj.labels.complete(traj)
    assert full.coordinate == tuple(f"q{i}" for i in range(model.nq)) and len(full.velocity) == model.nv


def test_a_mechanism_names_its_coordinates_and_velocities() -> None:
    cart = NamedCart()
    drive = gp.Force(lambda q, v, t: ca.DM([[1, 0]]))
    model = gp.Model(cart, gp.Holonomic(lambda q, t: q[0] - 0.1 * t, name="drive", realization=drive))
    traj = gp.simulate(model, [0.0, 0.3], [0.1, 0.0], 0.5)
    assert traj.labels.coordinate == ("x", "phi") and traj.labels.unknown == ("drive",)
    df = traj.to_pandas()
    assert {"q[x]", "q[phi]", "v[x]", "v[phi]", "u[drive]", "residual[drive]"} <= set(df.columns)
    ds = traj.to_xarray()
    assert list(ds["velocity"].values) == ["x", "phi"]  # v = q̇: the coordinates' names
    np.testing.assert_array_equal(ds["q"].sel(coordinate="phi").values, traj.q[:, 1])


def test_to_xarray_dims_variables_and_attributes(pendulum: tuple[gp.Model, gp.Trajectory]) -> None:
    model, traj = pendulum
    ds = traj.to_xarray()
    assert ds.sizes["time"] == len(traj) and ds.sizes["row"] == model.k and ds.sizes["unknown"] == model.m
    assert ds["q"].dims == ("time", "coordinate") and ds["u"].dims == ("time", "unknown")
    assert ds["residual"].dims == ("time", "row") and ds["contact_force"].dims == ("time", "contact_row")
    for key in ("a", "lam", "reaction", "compulsion", "margin", "g", "energy", "work_reaction", "energy_balance"):
        assert key in ds and ds[key].attrs["long_name"]
    assert ds["margin"].attrs["units"] == "1"
    assert list(ds["row"].values) == model.row_names
    for key in ("method", "solver", "lane", "route", "status", "message"):
        assert ds.attrs[key] == getattr(traj, key)
    assert ds.attrs["steps"] == traj.steps and ds.attrs["rhs_evaluations"] == traj.rhs_evaluations
    np.testing.assert_array_equal(ds["u"].values, traj.u)


def test_to_pandas_is_indexed_by_time(pendulum: tuple[gp.Model, gp.Trajectory]) -> None:
    model, traj = pendulum
    df = traj.to_pandas()
    assert df.index.name == "t" and len(df) == len(traj)
    np.testing.assert_array_equal(df.index.values, traj.t)
    for row in model.row_names:
        assert f"u[{row}]" in df.columns and f"residual[{row}]" in df.columns
    np.testing.assert_array_equal(df["q[q0]"].values, traj.q[:, 0])
    assert df.attrs["method"] == traj.method and "margin" in df.columns


@pytest.mark.parametrize("suffix", [".npz", ".nc"])
def test_round_trip_keeps_arrays_names_settings_and_the_verdict(
    tmp_path: Path, suffix: str, pendulum: tuple[gp.Model, gp.Trajectory]
) -> None:
    model, traj = pendulum
    back = gp.load_trajectory(traj.save(tmp_path / f"pendulum{suffix}"))
    for key in ("t", "q", "v", "a", "u", "reaction", "residual", "g", "margin", "compulsion", "energy"):
        np.testing.assert_array_equal(getattr(back, key), getattr(traj, key))
    assert back.labels == traj.labels
    assert (back.status, back.method, back.solver, back.lane, back.route, back.steps) == (
        traj.status,
        traj.method,
        traj.solver,
        traj.lane,
        traj.route,
        traj.steps,
    )
    before, after = gp.verify(model, traj), gp.verify(model, back)
    assert before.is_motion and after.is_motion and after.message == before.message


@pytest.mark.parametrize("suffix", [".npz", ".nc"])
def test_a_contact_run_round_trips_with_its_events(
    tmp_path: Path, suffix: str, block: tuple[gp.Model, gp.Trajectory]
) -> None:
    model, traj = block
    back = gp.load_trajectory(traj.save(tmp_path / f"block{suffix}"))
    np.testing.assert_array_equal(back.contact_force, traj.contact_force)
    np.testing.assert_array_equal(back.gap, traj.gap)
    assert back.labels.contact_row == tuple(model.contact_row_names)
    assert [e["kind"] for e in back.events] == [e["kind"] for e in traj.events] and traj.events
    before, after = gp.verify(model, traj), gp.verify(model, back)
    assert after.is_motion == before.is_motion and after.message == before.message


def test_a_wrong_run_stays_wrong_after_the_round_trip(tmp_path: Path, pendulum: tuple[gp.Model, gp.Trajectory]) -> None:
    model, traj = pendulum
    wrong = replace(traj, v=traj.v * (1 + 1e-3), q=traj.q)
    back = gp.load_trajectory(wrong.save(tmp_path / "wrong.npz"))
    before, after = gp.verify(model, wrong, constraint_tol=1.0), gp.verify(model, back, constraint_tol=1.0)
    assert not before.is_motion and not after.is_motion and after.message == before.message


def test_save_refuses_an_unknown_suffix_and_load_a_foreign_file(tmp_path: Path, pendulum: tuple) -> None:
    _, traj = pendulum
    with pytest.raises(gp.InputError, match=r"\.npz or \.nc"):
        traj.save(tmp_path / "run.csv")
    np.savez(tmp_path / "other.npz", x=np.zeros(2))
    with pytest.raises(gp.InputError, match="not a trajectory"):
        gp.load_trajectory(tmp_path / "other.npz")
    with pytest.raises(gp.InputError, match="no such file"):
        gp.load_trajectory(tmp_path / "missing.npz")


def test_a_hand_made_trajectory_gets_generic_names(pendulum: tuple) -> None:
    _, traj = pendulum
    bare = replace(traj, labels=Labels())
    ds = bare.to_xarray()
    assert list(ds["row"].values) == [f"row{i}" for i in range(traj.residual.shape[1])]
    assert "u[u0]" in bare.to_pandas().columns


def test_without_the_extra_the_views_say_what_to_install(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, pendulum: tuple
) -> None:
    _, traj = pendulum
    monkeypatch.setitem(sys.modules, "xarray", None)
    monkeypatch.setitem(sys.modules, "pandas", None)
    for call in (traj.to_xarray, traj.to_pandas, lambda: traj.save(tmp_path / "run.nc")):
        with pytest.raises(gp.GaussppError, match=r"pip install 'gausspp\[data\]'"):
            call()
    assert gp.load_trajectory(traj.save(tmp_path / "run.npz")).labels == traj.labels  # npz: numpy only


def test_importing_gausspp_does_not_import_xarray_or_pandas() -> None:
    code = "import sys, gausspp; print(sorted(m for m in ('xarray', 'pandas') if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"


@pytest.mark.parametrize("name", ["run.npz", "run.nc", "dir"])
def test_the_cli_writes_a_loadable_file(tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / name
    assert cli.main(["run", "pendulum", "--t-end", "0.5", "--out", str(out)]) == 0
    capsys.readouterr()
    path = out / "pendulum.npz" if name == "dir" else out
    back = gp.load_trajectory(path)
    scene = gp.scenes.get("pendulum")
    assert back.success and back.t[-1] == 0.5 and back.labels.row == tuple(scene.model.row_names)
    assert gp.verify(scene.model, back).is_motion
