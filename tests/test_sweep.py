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

import pytest

from gausspp.errors import InputError
from gausspp.sweep import SweepError, grid, realizability_task, simulate_task, sweep

ROOT = Path(__file__).resolve().parents[1]


# -- tasks used by the tests: top level, so that worker processes can unpickle them --------------------
def counted_task(params: dict[str, Any]) -> dict[str, float]:
    """Deterministic, slow enough to be killed midway; logs each execution to ``params['log']``."""
    with open(params["log"], "a", encoding="utf-8") as fh:
        fh.write(f"{params['i']}\n")
    time.sleep(params.get("sleep", 0.0))
    x = float(params["i"])
    return {"y": x * x / 7.0 + 0.1, "z": x**0.5}


def failing_task(params: dict[str, Any]) -> dict[str, float]:
    if params["i"] == 3:
        raise ValueError("no good at i=3")
    return {"y": params["i"] / 3.0}


def _realizability_params() -> list[dict[str, Any]]:
    return grid(lon=[-150.0, -60.0, 0.0, 45.0, 120.0], lat=[-60.0, 0.0, 35.3, 80.0], inertia=[[1.0, 2.0, 3.0]])


def _simulate_params() -> list[dict[str, Any]]:
    return grid(omega0=[1.0], v_scale=[0.5, 1.0, 1.5], phi0=[0.0, 0.4], t_end=[0.02])


def test_grid_is_the_cartesian_product_in_order() -> None:
    assert grid(a=[1, 2], b="xy") == [{"a": 1, "b": "x"}, {"a": 1, "b": "y"}, {"a": 2, "b": "x"}, {"a": 2, "b": "y"}]


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
    records = [json.loads(line) for line in out.read_text().splitlines()]
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
from gausspp.sweep import grid, sweep
from tests.test_sweep import counted_task
sweep(counted_task, grid(i=range({n}), log=[sys.argv[1]], sleep=[0.03]), chunk=1, out=sys.argv[2], progress=False)
"""


def test_killed_sweep_resumes_without_recomputing(tmp_path: Path) -> None:
    n = 40
    log, out = tmp_path / "executions.log", tmp_path / "sweep.jsonl"
    params = grid(i=range(n), log=[str(log)], sleep=[0.03])
    proc = subprocess.Popen(
        [sys.executable, "-c", _KILLED.format(n=n), str(log), str(out)], cwd=ROOT, start_new_session=True
    )
    try:
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and (not out.exists() or len(out.read_text().splitlines()) < 8):
            time.sleep(0.01)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its pool workers, mid-flight
        proc.wait()
    before = {json.loads(line)["index"] for line in out.read_text().splitlines() if line.endswith("}")}
    assert 8 <= len(before) < n, "the sweep must be killed midway"
    log.write_text("")

    resumed = sweep(counted_task, params, executor="serial", out=out, progress=False)
    executed = [int(line) for line in log.read_text().split()]
    assert sorted(executed) == sorted(set(range(n)) - before)  # no finished task computed again
    assert resumed.computed == n - len(before)
    uninterrupted = sweep(counted_task, params, executor="serial", progress=False)
    assert resumed.results == uninterrupted.results and resumed.ok
    assert len({json.loads(line)["index"] for line in out.read_text().splitlines() if line.endswith("}")}) == n


def test_cli_sweep_realizability_writes_and_resumes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from gausspp.cli import main

    out = tmp_path / "map.jsonl"
    argv = ["sweep", "realizability", "--resolution", "10", "--workers", "1", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    assert "computed 703 " in capsys.readouterr().out and len(out.read_text().splitlines()) == 703
    assert main(argv) == 0
    assert "computed 0 " in capsys.readouterr().out
    assert main(["sweep", "realizability", "--resolution", "0"]) == 2
