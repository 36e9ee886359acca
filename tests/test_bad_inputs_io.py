"""Bad inputs of the step, the files, the sweeps and the cache answered by name (issue 42, item 4): each was a numpy
or Python exception, a vague message or silence."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp.studies import sweeps


def test_disagreement_with_a_step_of_another_model_names_the_mismatch() -> None:
    """Was numpy's broadcasting ValueError."""
    pendulum, masses = gp.scenes.get("pendulum"), gp.scenes.get("two-masses")
    mine = pendulum.model.step(0.0, pendulum.q0, pendulum.v0)
    other = masses.model.step(0.0, masses.q0, masses.v0)
    with pytest.raises(gp.ShapeError, match="another model"):
        mine.disagreement(other)
    with pytest.raises(gp.InputError, match="StepResult"):
        mine.disagreement("qp")  # type: ignore[arg-type]
    same = pendulum.model.step(0.0, pendulum.q0, pendulum.v0, solver="direct")
    assert mine.disagreement(same) < 1e-10  # the control: two solutions of one step compare


@pytest.mark.parametrize(
    ("field", "value", "named"),
    [("J", np.zeros((2, 4)), "J has shape"), ("phi", np.zeros(5), "phi has 5 entries"), ("D", np.zeros((4, 2)), "D")],
)
def test_solve_names_the_array_of_the_wrong_shape(field: str, value: np.ndarray, named: str) -> None:
    """A problem edited with ``dataclasses.replace`` skipped ``StepProblem.create``'s checks: numpy's broadcasting
    error came out of the kernel."""
    scene = gp.scenes.get("pendulum")
    problem = scene.model.step_data(0.0, scene.q0, scene.v0)
    with pytest.raises(gp.ShapeError, match=named):
        gp.solve(replace(problem, **{field: value}))
    assert np.allclose(gp.solve(problem).a, scene.model.step(0.0, scene.q0, scene.v0).a)  # the control


def test_solve_refuses_what_is_not_a_step_problem() -> None:
    with pytest.raises(gp.InputError, match="StepProblem"):
        gp.solve({"A": np.eye(2)})  # type: ignore[arg-type]


def test_loading_a_plain_text_file_says_what_was_expected(tmp_path: Path) -> None:
    """Was "it holds Python objects" for a text file."""
    path = tmp_path / "notes.npz"
    path.write_text("t q v\n0 1 2\n")
    with pytest.raises(gp.InputError, match=r"expected the \.npz archive .* Trajectory\.save"):
        gp.load_trajectory(path)


def test_saving_under_a_regular_file_names_the_file(tmp_path: Path) -> None:
    """Was Python's NotADirectoryError on the temporary name."""
    scene = gp.scenes.get("pendulum")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 0.05)
    blocker = tmp_path / "x.txt"
    blocker.write_text("a file")
    with pytest.raises(gp.InputError, match="x.txt' is a file, not a directory"):
        traj.save(blocker / "traj.npz")
    assert blocker.read_text() == "a file"
    assert gp.load_trajectory(traj.save(tmp_path / "traj.npz")).t.size == traj.t.size  # the control


def test_a_grid_with_an_empty_axis_names_it() -> None:
    """Was an empty grid: a sweep of nothing, silently."""
    with pytest.raises(gp.InputError, match="grid axis m=\\[\\] is empty"):
        sweeps.grid(m=[], L=[1.0, 2.0])
    assert len(sweeps.grid(m=[1.0], L=[1.0, 2.0])) == 2


def test_a_sweep_task_names_a_non_numeric_or_missing_parameter() -> None:
    """Were Python's ValueError (float('abc')) and KeyError ('lat')."""
    with pytest.raises(gp.InputError, match="simulate_task: the parameter t_end='abc' must be a number"):
        sweeps.simulate_task({"scene": "pendulum", "t_end": "abc"})
    with pytest.raises(gp.InputError, match="realizability_task: the parameter 'lat' is missing"):
        sweeps.realizability_task({"lon": 10.0})
    assert "margin" in sweeps.realizability_task({"lon": 10.0, "lat": 20.0})  # the control


CACHE_CHILD = r"""
import json, sys, numpy as np, gausspp as gp
from gausspp import disk_cache
sc = gp.scenes.get("planar-chain", N=int(sys.argv[1]))
tr = gp.simulate(sc.model, sc.q0, sc.v0, 0.02, dt=1e-3, method="rk4", solver="direct")
print(json.dumps({"counts": disk_cache.counts, "q": tr.q[-1].tolist()}))
"""


def _child(folder: Path, n: int) -> dict:
    import json

    env = {**os.environ, "GAUSSPP_CACHE_DIR": str(folder)}
    done = subprocess.run([sys.executable, "-c", CACHE_CHILD, str(n)], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_cache_file_holding_another_valid_function_is_rebuilt(tmp_path: Path) -> None:
    """Every file of one model's cache replaced by valid functions of another model's: each is rebuilt (its
    signature names its key and its bytes), and the run is the one it was."""
    a, b = tmp_path / "a", tmp_path / "b"
    first = _child(a, 3)
    _child(b, 4)
    files_a, files_b = sorted(a.glob("*.casadi")), sorted(b.glob("*.casadi"))
    assert files_a and files_b
    for i, path in enumerate(files_a):  # another model's valid function under this model's name
        shutil.copyfile(files_b[i % len(files_b)], path)
    again = _child(a, 3)
    assert again["counts"]["loaded"] == 0 and again["counts"]["built"] == first["counts"]["built"]
    assert again["q"] == first["q"]
    trusted = _child(a, 3)  # the control: its own rebuilt files are loaded
    assert trusted["counts"]["loaded"] == first["counts"]["built"]


def test_simulate_friction_refuses_record_times_outside_the_run() -> None:
    """Were dropped silently."""
    from gausspp.friction import scenes as friction_scenes

    mech, contacts = friction_scenes.box(0.3)
    q0, v0 = [0.0, 0.1, 0.0], [1.0, 0.0, 0.0]
    with pytest.raises(gp.InputError, match=r"simulate_friction: record times must lie within \[t0, t_end\]"):
        gp.simulate_friction(mech, contacts, q0, v0, 0.1, record=[0.05, 0.2])
    run = gp.simulate_friction(mech, contacts, q0, v0, 0.1, record=[0.05, 0.1])
    assert 0.05 in run.t


def test_run_out_naming_an_existing_file_is_refused_without_a_traceback(tmp_path: Path) -> None:
    blocker = tmp_path / "afile"
    blocker.write_text("x")
    done = subprocess.run(
        [sys.executable, "-m", "gausspp.cli", "run", "pendulum", "--out", str(blocker)], capture_output=True, text=True
    )
    assert done.returncode != 0
    assert "is a file" in done.stderr and "Traceback" not in done.stderr
    assert blocker.read_text() == "x"


def test_simulate_servo_refuses_record_times_outside_the_run() -> None:
    """Was scipy's "Values in 't_eval' are not within 't_span'" (a helper's review found this entry point)."""
    scene = gp.scenes.get("overhead-crane")
    with pytest.raises(gp.InputError, match=r"simulate_servo: record times must lie within \[t0, t_end\]"):
        gp.simulate_servo(scene.model, scene.q0, scene.v0, 0.5, record=[0.1, 0.9])
    assert gp.simulate_servo(scene.model, scene.q0, scene.v0, 0.5, record=[0.1, 0.5]).t.size == 2  # the control


def test_a_sweep_log_under_a_regular_file_says_it_is_a_file(tmp_path: Path) -> None:
    """Was "[Errno 17] File exists"."""
    blocker = tmp_path / "f.txt"
    blocker.write_text("x")
    with pytest.raises(gp.GaussppError, match="f.txt' is a file, not a folder"):
        sweeps.sweep(sweeps.realizability_task, [{"lon": 0.0, "lat": 0.0}], out=blocker / "x.jsonl")


def test_report_out_naming_a_file_is_refused_before_the_study(tmp_path: Path) -> None:
    """Was refused only after the whole study had run ("cannot write …: File exists")."""
    blocker = tmp_path / "f.txt"
    blocker.write_text("x")
    done = subprocess.run(
        [sys.executable, "-m", "gausspp.cli", "report", "--out", str(blocker)], capture_output=True, text=True
    )
    assert done.returncode != 0 and "is a file" in done.stderr and "Traceback" not in done.stderr
    assert "runs in" not in done.stdout  # no study was run first
    assert blocker.read_text() == "x"
