"""No file that existed before a call is changed by it unless the call says so; what is saved loads back; a file
that is not one gausspp wrote is refused with a gausspp error naming it (issue 28, items 1–2)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp.studies.sweeps import SweepError, grid


@pytest.fixture(scope="module")
def traj() -> gp.Trajectory:
    scene = gp.scenes.get("pendulum")
    return gp.simulate(scene.model, scene.q0, scene.v0, 0.1)


def test_save_refuses_to_overwrite_a_file_it_did_not_write(tmp_path: Path, traj: gp.Trajectory) -> None:
    mine = tmp_path / "mine.npz"
    mine.write_text("my notes")
    with pytest.raises(gp.InputError, match="mine.npz.*exists and is not a trajectory.*overwrite=True"):
        traj.save(mine)
    assert mine.read_text() == "my notes"
    traj.save(mine, overwrite=True)  # the call says so
    assert len(gp.load_trajectory(mine)) == len(traj)
    traj.save(mine)  # a saved trajectory is replaced by the next save without asking
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.npz"]  # no temporary file left behind


def test_a_refused_save_leaves_the_good_file_as_it_was(tmp_path: Path, traj: gp.Trajectory) -> None:
    good = traj.save(tmp_path / "good.npz")
    before = good.read_bytes()
    for attrs in ({"t": "hello"}, {"note": [1, 2]}, {"bad key": 1}, {"x": float("nan")}):
        with pytest.raises(gp.InputError, match="attrs"):
            traj.save(good, attrs=attrs)  # type: ignore[arg-type]
        assert good.read_bytes() == before
    kept = traj.save(good, attrs={"scene": "pendulum", "run": 3})
    assert kept == good and len(gp.load_trajectory(good)) == len(traj)


def test_the_path_returned_is_the_path_written(tmp_path: Path, traj: gp.Trajectory) -> None:
    written = traj.save(tmp_path / "run.NPZ")
    assert written.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["run.NPZ"]
    np.testing.assert_array_equal(gp.load_trajectory(written).q, traj.q)


@pytest.mark.parametrize(
    ("name", "content", "why"),
    [
        ("empty.npz", b"", "empty"),
        ("array.npz", None, "single array"),
        ("text.nc", b"hello", "no netCDF reader"),
        ("trunc.npz", "half", "not a numpy archive"),
        ("missing.npz", "absent", "no such file"),
    ],
)
def test_a_file_that_is_no_trajectory_is_named_in_a_gausspp_error(
    tmp_path: Path, traj: gp.Trajectory, name: str, content: object, why: str
) -> None:
    path = tmp_path / name
    if content is None:
        with path.open("wb") as fh:
            np.save(fh, np.zeros(3))
    elif content == "half":
        whole = traj.save(tmp_path / "whole.npz").read_bytes()
        path.write_bytes(whole[: len(whole) // 2])
    elif isinstance(content, bytes):
        path.write_bytes(content)
    with pytest.raises(gp.InputError, match=rf"{name}.*{why}") as caught:
        gp.load_trajectory(path)
    assert "allow_pickle" not in str(caught.value)


def _square(p: dict) -> dict:
    return {"y": p["x"] ** 2}


@pytest.mark.parametrize("name", ["saved.npz", "journal.txt"])
def test_a_sweep_never_writes_over_another_file(tmp_path: Path, traj: gp.Trajectory, name: str) -> None:
    """``out=`` naming a saved trajectory or an unrelated text file is refused before any task runs."""
    path = tmp_path / name
    if name.endswith(".npz"):
        traj.save(path)
    else:
        path.write_text("dear diary\n")
    before = path.read_bytes()
    with pytest.raises(SweepError, match="exists and is not a sweep's output"):
        gp.sweep(_square, grid(x=[1, 2]), executor="serial", out=path, progress=False)
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == [name]
    ok = gp.sweep(_square, grid(x=[1, 2]), executor="serial", out=tmp_path / "sweep.npz", progress=False)
    again = gp.sweep(_square, grid(x=[1, 2]), executor="serial", out=tmp_path / "sweep.npz", progress=False)
    assert [r["y"] for r in ok.results] == [r["y"] for r in again.results] == [1, 4]  # its own output resumes


def test_the_command_line_refuses_an_out_it_would_damage(tmp_path: Path) -> None:
    mine = tmp_path / "mine.npz"
    mine.write_text("my notes")
    a_file = tmp_path / "afile"
    a_file.write_text("x")
    for out in (mine, a_file, a_file / "sub"):
        done = subprocess.run(
            [sys.executable, "-m", "gausspp.cli", "run", "pendulum", "--t-end", "0.05", "--out", str(out)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert done.returncode != 0 and done.stderr.startswith("gausspp: error:") and "Traceback" not in done.stderr
        assert str(out.name) in done.stderr or str(a_file.name) in done.stderr
    assert mine.read_text() == "my notes" and a_file.read_text() == "x"


def test_a_step_longer_than_the_run_and_unordered_record_times_are_refused() -> None:
    scene = gp.scenes.get("pendulum")
    with pytest.raises(gp.InputError, match=r"dt=10 is longer than the run"):
        gp.simulate(scene.model, scene.q0, scene.v0, 2.0, method="rk4", dt=10.0)
    with pytest.raises(gp.InputError, match=r"dt=0.5 is longer than the run"):
        gp.simulate(scene.model, scene.q0, scene.v0, 0.01, method="RK45", dt=0.5)
    with pytest.raises(gp.InputError, match=r"record times must increase.*record\[0\] = 0.005"):
        gp.simulate(scene.model, scene.q0, scene.v0, 1.0, record=[0.005, 0.0, 0.01])
    with pytest.raises(gp.InputError, match=r"record times must increase"):
        gp.simulate(scene.model, scene.q0, scene.v0, 1.0, record=[0.0, 0.5, 0.5])


def test_acceleration_qp_accepts_zero_entries_that_carry_round_off() -> None:
    """Symmetry is judged on the matrix as a whole: two vanishing entries −2.8e-18 and −2.7e-18 are symmetric;
    an asymmetry of 1e-6 relative is refused (the control)."""
    rng = np.random.default_rng(3)
    B = rng.standard_normal((4, 4))
    A = B @ B.T + 4 * np.eye(4)
    A[0, 3], A[3, 0] = -2.8e-18, -2.7e-18
    J, phi, a0 = rng.standard_normal((1, 4)), np.array([0.3]), rng.standard_normal(4)
    sol = gp.acceleration_qp(A, a0, J, phi, J.T)
    np.testing.assert_allclose(J @ sol.a, phi, atol=1e-10)
    A[0, 1] += 1e-6 * np.abs(A).max()
    with pytest.raises(gp.NotPositiveDefiniteError, match="not symmetric"):
        gp.acceleration_qp(A, a0, J, phi, J.T)


def test_the_command_line_ends_quietly_when_its_reader_goes_and_refuses_an_animation_path_first(
    tmp_path: Path,
) -> None:
    piped = subprocess.run(
        f"{sys.executable} -m gausspp.cli scenes | head -1", shell=True, capture_output=True, text=True, timeout=300
    )
    assert piped.returncode == 0 and len(piped.stdout.splitlines()) == 1
    assert "Error" not in piped.stderr and "Traceback" not in piped.stderr
    a_file = tmp_path / "afile"
    a_file.write_text("x")
    done = subprocess.run(
        [sys.executable, "-m", "gausspp.cli", "run", "pendulum", "--t-end", "0.05", "--animate", str(a_file / "a.gif")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 1 and "is a file, not a directory" in done.stderr
    assert done.stdout == ""  # refused before the run: no summary printed


def _dies_once(p: dict) -> dict:
    """The task of x = 3 kills its worker process the first time it runs (a marker file says it did)."""
    import os
    import signal

    marker = Path(p["marker"])
    if p["x"] == 3 and not marker.exists():
        marker.write_text("killed")
        os.kill(os.getpid(), signal.SIGKILL)
    return {"y": p["x"] ** 2}


def test_a_sweep_survives_a_killed_worker_on_the_local_pool_and_says_where_it_stands_on_a_given_one(
    tmp_path: Path,
) -> None:
    """Issue 28, item 5: the local pool restarts and finishes (every result right); a pool the caller passed ends
    in a SweepError counting what is done, and the same call with out= resumes the rest."""
    from concurrent.futures import ProcessPoolExecutor

    params = grid(x=list(range(8)), marker=[str(tmp_path / "local")])
    local = gp.sweep(_dies_once, params, chunk=1, progress=False)
    assert (tmp_path / "local").exists()  # a worker was killed
    assert [r["y"] for r in local.results] == [x**2 for x in range(8)] and not local.errors
    params = grid(x=list(range(8)), marker=[str(tmp_path / "given")])
    log = tmp_path / "sweep.jsonl"
    with ProcessPoolExecutor(2) as pool:
        with pytest.raises(SweepError, match=r"a worker process died \(the executor passed in\): \d of 8 tasks are"):
            gp.sweep(_dies_once, params, executor=pool, chunk=1, out=log, progress=False)
    resumed = gp.sweep(_dies_once, params, executor="serial", out=log, progress=False)
    assert [r["y"] for r in resumed.results] == [x**2 for x in range(8)] and not resumed.errors


def test_a_sweep_on_a_dask_cluster_survives_a_killed_worker(tmp_path: Path) -> None:
    """The other executor: dask's nanny restarts the killed worker and the scheduler runs its task again."""
    distributed = pytest.importorskip("distributed", reason="dask[distributed] is not installed (pip install .[dask])")
    params = grid(x=list(range(8)), marker=[str(tmp_path / "dask")])
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        result = gp.sweep(_dies_once, params, executor=client, chunk=1, progress=False)
    assert (tmp_path / "dask").exists()  # a worker was killed
    assert [r["y"] for r in result.results] == [x**2 for x in range(8)] and not result.errors
