"""Sweeps: same results on every executor, nothing lost when killed midway, failures recorded."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gausspp.errors import InputError, UnknownNameError
from gausspp.studies.sweeps import SweepError, SweepResult, grid, realizability_task, simulate_task, sweep

ROOT = Path(__file__).resolve().parents[1]


def _records(out: Path) -> list[dict[str, Any]]:
    """The task records of a JSON-lines log (after its first line, which names the task)."""
    lines = out.read_text().splitlines()
    assert "task" in json.loads(lines[0]) and "index" not in json.loads(lines[0])
    return [json.loads(line) for line in lines[1:] if line.endswith("}")]


# -- tasks used by the tests: top level, so that worker processes can unpickle them --------------------
def counted_task(params: dict[str, Any]) -> dict[str, float]:
    """Deterministic; logs each execution to ``params['log']``. With ``params['gate']`` (a path), tasks from
    ``params['held_from']`` on wait until that file exists (at most 10 min): a sweep held there is killed midway
    whatever the machine's speed."""
    with open(params["log"], "a", encoding="utf-8") as fh:
        fh.write(f"{params['i']}\n")
    time.sleep(params.get("sleep", 0.0))
    if params.get("gate") and params["i"] >= params["held_from"]:
        deadline = time.monotonic() + 600
        while not os.path.exists(params["gate"]) and time.monotonic() < deadline:
            time.sleep(0.01)
    x = float(params["i"])
    return {"y": x * x / 7.0 + 0.1, "z": x**0.5}


def failing_task(params: dict[str, Any]) -> dict[str, float]:
    if params["i"] == 3:
        raise ValueError("no good at i=3")
    return {"y": params["i"] / 3.0}


def mixed_task(params: dict[str, Any]) -> dict[str, Any]:
    """Numbers, a list and a string per task; fails at i=3."""
    i = params["i"]
    if i == 3:
        raise RuntimeError("no result at i=3")
    return {"y": i / 3.0, "vec": [i, 2.0 * i], "label": f"p{i}", "flag": i % 2 == 0}


def _realizability_params() -> list[dict[str, Any]]:
    return grid(lon=[-150.0, -60.0, 0.0, 45.0, 120.0], lat=[-60.0, 0.0, 35.3, 80.0], inertia=[[1.0, 2.0, 3.0]])


def _simulate_params() -> list[dict[str, Any]]:
    return grid(omega0=[1.0], v_scale=[0.5, 1.0, 1.5], phi0=[0.0, 0.4], t_end=[0.02], dt=[1e-3])


def test_grid_is_the_cartesian_product_in_order() -> None:
    assert grid(a=[1, 2], b=["x", "y"]) == [
        {"a": 1, "b": "x"},
        {"a": 1, "b": "y"},
        {"a": 2, "b": "x"},
        {"a": 2, "b": "y"},
    ]


@pytest.mark.parametrize("task, make", [(realizability_task, _realizability_params), (simulate_task, _simulate_params)])
def test_serial_and_process_pool_agree_bitwise(task: Any, make: Any) -> None:
    params = make()
    serial = sweep(task, params, executor="serial", progress=False)
    with ProcessPoolExecutor(2) as pool:
        pooled = sweep(task, params, executor=pool, chunk=3, progress=False)
    assert serial.ok and pooled.ok
    assert serial.results == pooled.results  # float == float after the same JSON round trip: bitwise
    assert serial.params == pooled.params == params
    assert serial.computed == len(params)


def test_dask_local_cluster_agrees_bitwise() -> None:
    distributed = pytest.importorskip("distributed", reason="dask[distributed] is not installed (pip install .[dask])")
    serial_r = sweep(realizability_task, _realizability_params(), executor="serial", progress=False)
    serial_s = sweep(simulate_task, _simulate_params(), executor="serial", progress=False)
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        dask_r = sweep(realizability_task, _realizability_params(), executor=client, chunk=4, progress=False)
        dask_s = sweep(simulate_task, _simulate_params(), executor=client.get_executor(), progress=False)
    assert dask_r.ok and dask_s.ok
    assert dask_r.results == serial_r.results and dask_s.results == serial_s.results


def test_failed_task_is_recorded_and_the_others_complete(tmp_path: Path) -> None:
    out = tmp_path / "sweep.jsonl"
    res = sweep(failing_task, grid(i=range(6)), executor="serial", out=out, progress=False)
    assert list(res.errors) == [3] and "ValueError: no good at i=3" in res.errors[3]
    assert res.results[3] is None and [r["y"] for r in res.results if r] == [i / 3.0 for i in (0, 1, 2, 4, 5)]
    records = _records(out)
    assert sorted(r["index"] for r in records) == list(range(6))
    assert [r["error"] for r in records if "error" in r] == [res.errors[3]]
    # a resume keeps the recorded failure without running anything; retry_failed runs it again
    again = sweep(failing_task, grid(i=range(6)), executor="serial", out=out, progress=False)
    assert again.computed == 0 and again.errors == res.errors and again.results == res.results
    retried = sweep(failing_task, grid(i=range(6)), executor="serial", out=out, progress=False, retry_failed=True)
    assert retried.computed == 1 and retried.errors.keys() == {3}


def test_out_file_of_another_sweep_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "sweep.jsonl"
    sweep(failing_task, grid(i=range(2)), executor="serial", out=out, progress=False)
    with pytest.raises(SweepError, match="another sweep"):
        sweep(failing_task, grid(i=[5, 6]), executor="serial", out=out, progress=False)


def test_bad_arguments_name_the_parameter() -> None:
    with pytest.raises(InputError, match="executor='threads'"):
        sweep(failing_task, grid(i=[1]), executor="threads")
    with pytest.raises(InputError, match="chunk"):
        sweep(failing_task, grid(i=[1]), executor="serial", chunk=0)
    with pytest.raises(InputError, match="JSON"):
        sweep(failing_task, [{"i": object()}], executor="serial")


_KILLED = """
import sys
from gausspp.studies.sweeps import grid, sweep
from tests.test_sweep import counted_task
params = grid(i=range({n}), log=[sys.argv[1]], gate=[sys.argv[3]], held_from=[10])
sweep(counted_task, params, chunk=1, out=sys.argv[2], progress=False)
"""


def test_killed_sweep_resumes_without_recomputing(tmp_path: Path) -> None:
    n = 40
    log, out, gate = tmp_path / "executions.log", tmp_path / "sweep.jsonl", tmp_path / "gate"
    params = grid(i=range(n), log=[str(log)], gate=[str(gate)], held_from=[10])
    proc = subprocess.Popen(
        [sys.executable, "-c", _KILLED.format(n=n), str(log), str(out), str(gate)], cwd=ROOT, start_new_session=True
    )
    try:  # tasks 0 … 9 finish, the others wait at the gate: kill once the ten are in the file
        deadline = time.monotonic() + 300  # only a hang reaches it
        while time.monotonic() < deadline and (not out.exists() or out.read_text().count("}\n") < 11):
            time.sleep(0.01)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its pool workers, mid-flight
        proc.wait()
    before = {r["index"] for r in _records(out)}
    assert before == set(range(10)), "the sweep must be killed midway, at the gate"
    log.write_text("")
    gate.touch()

    resumed = sweep(counted_task, params, executor="serial", out=out, progress=False)
    executed = [int(line) for line in log.read_text().split()]
    assert sorted(executed) == sorted(set(range(n)) - before)  # no finished task computed again
    assert resumed.computed == n - len(before)
    uninterrupted = sweep(counted_task, params, executor="serial", progress=False)
    assert resumed.results == uninterrupted.results and resumed.ok
    assert len({r["index"] for r in _records(out)}) == n


def test_cli_sweep_realizability_writes_and_resumes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from gausspp.cli import main

    out = tmp_path / "map.jsonl"
    argv = ["sweep", "realizability", "--resolution", "10", "--workers", "1", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    assert "computed 703 " in capsys.readouterr().out and len(_records(out)) == 703
    assert main(argv) == 0
    assert "computed 0 " in capsys.readouterr().out
    assert main(["sweep", "realizability", "--resolution", "0"]) == 2


# -- the spelling: gausspp.sweep(fn_or_scene, ...) ----------------------------------------------
def test_gausspp_sweep_is_the_function_and_gausspp_sweeps_the_module() -> None:
    import gausspp

    assert gausspp.sweep is gausspp.sweeps.sweep and callable(gausspp.sweep)
    res = gausspp.sweep(realizability_task, grid(lon=[0.0], lat=[10.0]), executor="serial", progress=False)
    assert res.ok and res.column("margin").shape == (1,)


def _pendulum_state(phi: float, omega: float) -> tuple[list[float], list[float]]:
    c, s = np.cos(phi), np.sin(phi)  # the pendulum scene's q = (x, z, φ) with L = 1, on its pins
    return [c, s, phi], [-s * omega, c * omega, omega]


def test_scene_name_runs_the_default_scene_task(tmp_path: Path) -> None:
    params = grid(omega0=[0.0, 0.7], t_end=[0.02])
    by_name = sweep("pendulum", params, executor="serial", progress=False)
    by_task = sweep(simulate_task, [{"scene": "pendulum", **p} for p in params], executor="serial", progress=False)
    assert by_name.ok and by_name.results == by_task.results and by_name.params == params
    assert set(by_name.results[0]) >= {"t_final", "steps", "residual", "energy_balance", "max_reaction", "min_margin"}
    assert np.allclose(by_name.column("t_final"), 0.02) and np.all(by_name.column("steps") == 2000)  # dt = t_end/2000
    assert np.all(by_name.column("q_error") < 1e-10)  # RK4 against the scene's reference motion
    assert np.all(by_name.column("residual") < 1e-8)
    # released level and at rest the pin carries m g Ic/(Ic + m L²) vertically, with its torque about the
    # centre of mass: |R| = √2 · 9.81 · 0.01/1.01 at t = 0; it grows as the body swings and with ω (centripetal)
    reaction = by_name.column("max_reaction")
    assert np.sqrt(2) * 9.81 * 0.01 / 1.01 <= reaction[0] < 0.2 and reaction[1] > reaction[0]
    assert by_name.column("q_end").shape == (2, 3)  # the final state, one row per task
    # initial data through q0/v0 (one model for every sample): the run starts there, no exact motion claimed
    q0, v0 = _pendulum_state(0.3, -0.4)
    moved = sweep("pendulum", [{"q0": q0, "v0": v0, "t_end": 0.02}], executor="serial", progress=False)
    assert moved.ok and "q_error" not in moved.results[0]
    taylor = 0.3 - 0.4 * 0.02 - 0.5 * 9.81 * np.cos(0.3) / 1.01 * 0.02**2  # φ0 + ω0 t + ½ φ̈0 t², O(t³) ≈ 2e-6
    assert moved.results[0]["q_end"][2] == pytest.approx(taylor, abs=1e-5)
    # initial data off the constraints: a recorded failure, not a crash
    off = sweep("pendulum", [{"q0": [0.0, 0.0, 0.0], "t_end": 0.02}], executor="serial", progress=False)
    assert "InitialDataError" in off.errors[0]
    # a log is bound to its task: another scene's sweep does not resume from it
    out = tmp_path / "pendulum.jsonl"
    sweep("pendulum", params[:1], executor="serial", out=out, progress=False)
    with pytest.raises(SweepError, match="task 'scene:pendulum', not 'scene:two-masses'"):
        sweep("two-masses", params[:1], executor="serial", out=out, progress=False)


def test_every_scene_runs_with_the_default_task() -> None:
    from gausspp import scenes

    # every scene with a one-step solution (not the servo scenes); contact and bounded-actuator ones get DOP853 and
    # the QP
    for name in scenes.names("equality") + scenes.names("general"):
        res = sweep(name, [{"t_end": 0.01}], executor="serial", progress=False)
        assert res.ok, (name, res.errors)
        assert res.column("t_final")[0] == pytest.approx(0.01), name
        if name in scenes.names("equality"):  # a saturated actuator may leave its constraint, by design
            assert res.column("residual")[0] < 1e-6, name


def test_bad_first_argument_and_params_are_named() -> None:
    with pytest.raises(UnknownNameError, match="neither a task function nor a scene.*pendulum"):
        sweep("pendulim", grid(i=[1]), executor="serial")
    with pytest.raises(InputError, match="task function"):
        sweep(42, grid(i=[1]), executor="serial")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="list of parameter dicts.*wrap a single point"):
        sweep(failing_task, {"i": 1}, executor="serial")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"params\[1\] must be a dict"):
        sweep(failing_task, [{"i": 1}, 2], executor="serial")  # type: ignore[list-item]
    with pytest.raises(InputError, match="grid axis t_end=0.5 must be a list"):
        grid(t_end=0.5)  # type: ignore[arg-type]
    with pytest.raises(SweepError, match="cannot be sent to worker processes.*top-level function"):
        with ProcessPoolExecutor(1) as pool:
            sweep(lambda p: {"y": 1.0}, grid(i=[1]), executor=pool)
    with pytest.raises(SweepError, match="Parquet"):
        sweep(failing_task, grid(i=[1]), executor="serial", out="x.parquet")
    res = sweep(failing_task, grid(i=[1]), executor="serial", progress=False)
    with pytest.raises(SweepError, match="no task's result has 'z'"):
        res.column("z")


# -- NPZ ---------------------------------------------------------------------------------------------------
def test_npz_columns_and_round_trip(tmp_path: Path) -> None:
    out = tmp_path / "sweep.npz"
    params = grid(i=range(5), tag=["a"])
    res = sweep(mixed_task, params, executor="serial", out=out, progress=False)
    assert out.exists() and (tmp_path / "sweep.jsonl").exists()  # the log beside it: resumable
    with np.load(out, allow_pickle=False) as data:
        assert data["index"].tolist() == [0, 1, 2, 3, 4]
        assert data["ok"].tolist() == [True, True, True, False, True]
        assert data["error"][3].startswith("RuntimeError: no result at i=3") and data["error"][0] == ""
        assert data["params.i"].dtype == np.int64 and data["params.i"].tolist() == [0, 1, 2, 3, 4]
        assert data["params.tag"].tolist() == ["a"] * 5
        y = data["results.y"]
        assert y.dtype == float and np.isnan(y[3]) and y[4] == 4 / 3.0  # bitwise: the float went through JSON
        assert data["results.vec"].shape == (5, 2) and np.isnan(data["results.vec"][3]).all()
        assert data["results.vec"][2].tolist() == [2.0, 4.0]
        assert data["results.label"].tolist() == ["p0", "p1", "p2", "", "p4"]
        assert np.isnan(data["results.flag"][3]) and data["results.flag"][2] == 1.0
    back = SweepResult.from_npz(out)
    assert (back.params, back.results, back.errors, back.computed) == (res.params, res.results, res.errors, 5)
    # a resume computes nothing and writes the same columns again
    again = sweep(mixed_task, params, executor="serial", out=out, progress=False)
    assert again.computed == 0 and SweepResult.from_npz(out).results == res.results
    assert res.column("vec").shape == (5, 2) and res.param("i").tolist() == [0, 1, 2, 3, 4]
    with pytest.raises(SweepError, match="not a number"):
        res.column("label")
    np.savez(tmp_path / "other.npz", x=np.zeros(2))
    with pytest.raises(SweepError, match="not a sweep"):
        SweepResult.from_npz(tmp_path / "other.npz")
    with pytest.raises(SweepError, match="cannot read"):
        SweepResult.from_npz(tmp_path / "missing.npz")


# -- the work-precision study as a sweep ------------------------------------------------------------------
def test_work_precision_sweep_gives_the_report_rows() -> None:
    from dataclasses import asdict

    from gausspp.studies import report, sweeps

    config = (["two-masses", "mixed-rate"], ["rk4", "DOP853"], ["direct", "casadi:qrqp"])
    expected = report.work_precision(*config, repeats=1)
    with ProcessPoolExecutor(2) as pool:
        rows, res = sweeps.work_precision(*config, repeats=1, executor=pool, progress=False)
    assert res.ok and res.computed == len(res) == len(expected) + 2  # + one reference task per scene
    assert [r["task"] for r in res.params[:2]] == ["reference", "reference"]

    def same(row: report.Row) -> dict[str, Any]:
        d = asdict(row)
        del d["wall_time"]  # measured, not computed
        return d

    assert [same(r) for r in rows] == [same(r) for r in expected]  # bitwise, through JSON and workers
    assert any(r.reference.startswith("rk4 (compiled)") for r in rows)  # mixed-rate: the computed reference
    with pytest.raises(UnknownNameError, match="solver 'nope'"):
        sweeps.work_precision(["two-masses"], ["rk4"], ["nope"])


def test_cli_sweep_work_precision_writes_the_report_and_resumes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from gausspp.cli import main

    argv = ["sweep", "work-precision", "--scenes", "two-masses", "--methods", "rk4", "DOP853", "--solvers"]
    argv += ["direct", "--repeats", "1", "--workers", "1", "--out", str(tmp_path), "--quiet"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    # rk4 (compiled lane): 3 dt; DOP853: 4 rtol
    assert "7 runs; computed 8 of 8 tasks" in text and "two-masses" in text and "rtol=1e-13" in text
    for name in ("work_precision.jsonl", "work_precision.csv", "work_precision.json"):
        assert (tmp_path / name).stat().st_size > 0
    records = json.loads((tmp_path / "work_precision.json").read_text())
    assert [r["method"] for r in records] == ["rk4"] * 3 + ["DOP853"] * 4 and all(
        r["status"] == "success" for r in records
    )
    assert len(_records(tmp_path / "work_precision.jsonl")) == 8
    assert main(argv) == 0  # resumed: nothing computed again, the same table
    assert "computed 0 of 8 tasks" in capsys.readouterr().out
    assert json.loads((tmp_path / "work_precision.json").read_text()) == records
    assert main(["sweep", "work-precision", "--resolution", "3"]) == 2
    assert main(["sweep", "realizability", "--scenes", "pendulum"]) == 2
    assert main(["sweep", "work-precision", "--solvers", "nope", "--out", str(tmp_path)]) == 2
    assert "--solvers: 'nope' is unknown" in capsys.readouterr().err
