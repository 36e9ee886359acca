"""The ``gausspp`` command line: every subcommand on good and bad input, exit codes, one-line errors."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp import cli
from gausspp.cli import console, params
from gausspp.studies import demo, runs
from gausspp.studies import demo_run as demo_plan

PNG = b"\x89PNG\r\n\x1a\n"


def _command(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """The real entry point, as a script would call it."""
    return subprocess.run([sys.executable, "-m", "gausspp.cli", *args], capture_output=True, text=True, timeout=timeout)


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("gausspp: error: ") and "Traceback" not in err
    return lines[0]


def _has_matplotlib() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


# -- scenes ---------------------------------------------------------------------------------------
def test_scenes_lists_every_scene_with_a_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["scenes"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == gp.scenes.names()
    assert all(len(line.split()) > 2 for line in lines)


def test_scenes_shows_one_scenes_parameters(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["scenes", "two-masses"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("two-masses: ") and "m1" in out and "realization" in out and "default 'ideal'" in out
    assert cli.main(["scenes", "mixed-rate"]) == 0  # a wrapper scene: its fixed `law` is not offered
    out = capsys.readouterr().out
    assert " beta " in out and " law " not in out


# -- run ------------------------------------------------------------------------------------------
def test_run_prints_a_summary_and_writes_the_trajectory(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = cli.main(["run", "two-masses", "--param", "realization=servo", "-p", "F=2", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0
    for key in ("status          success", "final v", "max |Φ|, |g|", "energy balance", "margin", "vs exact"):
        assert key in out
    assert "x₁′ = 0.666667 m/s, x₂′ = 0.666667 m/s" in out  # servo: both masses at F/m2
    data = np.load(tmp_path / "two-masses.npz")
    assert str(data["status"]) == "success" and data["t"][-1] == 1.0 and data["q"].shape == (501, 2)
    np.testing.assert_allclose(data["v"][-1], [2 / 3, 2 / 3], rtol=1e-12)
    header, *rows = (tmp_path / "two-masses.csv").read_text().splitlines()
    assert header.startswith("t,q1,q2,v1,v2,") and "margin" in header and len(rows) == 501
    if _has_matplotlib():
        assert (tmp_path / "two-masses.png").read_bytes()[:8] == PNG


def test_run_with_a_fixed_step_method_and_the_direct_solver(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", "rigid-body-servo", "-p", "n=(1, 0.2, 0)", "--method", "rk4", "--dt", "0.01", "--solver", "direct"]
    assert cli.main(argv) == 0
    out = capsys.readouterr().out
    assert "rk4 (dt 0.01) · step by direct" in out and "1000 steps" in out and "status          success" in out


def test_run_that_fails_midway_writes_what_it_computed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # theta0 near 0: the crane's servo loses the payload (margin ∝ sin²θ) about t = 1.15 of 3
    code = cli.main(["run", "crane", "--param", "theta0=-0.05", "--rtol", "1e-6", "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 1
    # the last state reached is kept (and written): its small margin is warned about, as with every step recorded
    *warned, last = captured.err.strip().splitlines()
    assert all(w.startswith("gausspp: warning: RealizabilityWarning: realizability margin") for w in warned)
    line = _one_error_line(last)
    assert "the run failed" in line and "RealizabilityError" in line
    assert "status          failed" in captured.out and "written" in captured.out
    data = np.load(tmp_path / "crane.npz")
    assert str(data["status"]) == "failed" and "RealizabilityError" in str(data["message"])
    assert 0.5 < data["t"][-1] < 3.0 and np.all(np.isfinite(data["q"]))


def test_run_by_the_real_entry_point() -> None:
    result = _command("run", "two-masses", "--t-end", "0.5")
    assert result.returncode == 0, result.stderr
    assert "status          success" in result.stdout and result.stderr == ""


# -- verify -----------------------------------------------------------------------------------------
def test_verify_accepts_the_scenes_own_motion(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["verify", "two-masses", "--expect", "motion"]) == 0
    out = capsys.readouterr().out
    assert "relative gap" in out and "tolerance" in out and "verdict:  a motion of the model" in out


def test_verify_rejects_the_rod_motion_as_a_servo_motion(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["verify", "two-masses", "--param", "realization=ideal", "--check-param", "realization=servo"]
    assert cli.main(argv) == 0  # the verification ran: exit 0 whatever the verdict
    out = capsys.readouterr().out
    assert "verdict:  NOT a motion of the model" in out and "rod: force" in out
    gap = float(out.split("relative gap")[1].split()[0])
    assert gap > 0.1
    assert cli.main([*argv, "--expect", "motion"]) == 1  # ... unless told what to expect
    assert "expected motion" in _one_error_line(capsys.readouterr().err)
    assert cli.main([*argv, "--expect", "not-motion"]) == 0


def test_verify_a_stiff_scene_on_its_accepted_steps(capsys: pytest.CaptureFixture[str]) -> None:
    # uniform samples would alias the fast oscillation; every accepted step resolves it
    assert cli.main(["verify", "stiff-chain", "--t-end", "2", "--quiet"]) == 0
    assert "verdict:  a motion of the model" in capsys.readouterr().out


# -- report, demo ----------------------------------------------------------------------------------
def test_report_for_one_scene(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["report", "--scenes", "two-masses", "--repeats", "1", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "two-masses" in out and "Fastest run" in out
    assert (tmp_path / "work_precision.csv").stat().st_size > 0


def test_report_figures_state_the_scene_parameters(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from gausspp.cli import commands

    seen: dict = {}
    monkeypatch.setattr(commands.plot, "save_work_precision", lambda rows, out, titles=None: seen.update(titles) or [])
    assert cli.main(["report", "--scenes", "two-masses", "--repeats", "1", "--out", str(tmp_path)]) == 0
    params = gp.scenes.get("two-masses").params
    assert set(seen) == {"two-masses"}
    assert "SI units" in seen["two-masses"]
    assert f"m1 = {params['m1']:g}" in seen["two-masses"] and f"F = {params['F']:g}" in seen["two-masses"]


def test_demo_by_the_real_entry_point(demo_run) -> None:
    assert demo_run.returncode == 0, demo_run.merged
    assert "Every scene" in demo_run.stdout
    for name in gp.scenes.names("equality"):
        assert f"\n{name} " in demo_run.stdout
    pngs = sorted(demo_run.out.glob("*.png"))  # the teaching figures
    assert len(pngs) == 4 and all(p.read_bytes()[:4] == b"\x89PNG" and p.stat().st_size > 10_000 for p in pngs)


# -- bad input: one line, the culprit named, the valid choices listed, a non-zero exit ---------------------
BAD = [
    # (argv, exit code, fragments of the error line)
    (["run", "nosuch"], 2, ["'nosuch'", "two-masses", "andrews"]),
    (["verify", "nosuch"], 2, ["'nosuch'", "two-masses"]),
    (["scenes", "nosuch"], 2, ["'nosuch'", "two-masses"]),
    (["report", "--scenes", "nosuch"], 2, ["'nosuch'", "two-masses"]),
    (["run", "two-masses", "--param", "m1=-1"], 1, ["m1=-1", "m1, m2 > 0"]),
    (["run", "two-masses", "--param", "m1=abc"], 2, ["m1=abc", "must be a number"]),
    (["run", "two-masses", "--param", "mass=2"], 2, ["'mass'", "m1, m2, F, realization"]),
    (["run", "two-masses", "--param", "m1"], 2, ["'m1'", "KEY=VALUE"]),
    (["run", "two-masses", "--param", "realization=spring"], 1, ["'spring'", "'ideal', 'servo'"]),
    (["run", "stiff-chain", "--param", "n=2.5"], 2, ["n=2.5", "integer"]),
    (["run", "rigid-body-servo", "--param", "n=abc"], 1, ["rigid-body-servo", "'abc'"]),
    (["run", "two-masses", "--solver", "magic"], 2, ["--solver", "'magic'", "'qp', 'direct'"]),
    (["run", "two-masses", "--method", "euler"], 2, ["--method", "'euler'", "'rk4'", "'DOP853'"]),
    (["run", "two-masses", "--backend", "nope"], 2, ["'nope'", "casadi:qrqp"]),
    (["run", "two-masses", "--backend", "casadi:osqp", "--solver", "direct"], 2, ["--backend", "--solver qp"]),
    (["run", "two-masses", "--method", "cvodes", "--solver", "qp"], 2, ["cvodes", "--solver direct"]),
    (["run", "two-masses", "--dt", "0"], 2, ["--dt", "positive"]),
    (["run", "two-masses", "--t-end", "abc"], 2, ["--t-end", "'abc'"]),
    (["verify", "two-masses", "--check-param", "m1=abc"], 2, ["--check-param", "m1=abc"]),
    (["verify", "two-masses", "--param", "m1=-1"], 1, ["m1=-1"]),
    (["verify", "two-masses", "--method", "euler"], 2, ["'euler'", "'DOP853'"]),
    (["run"], 2, ["SCENE"]),
    ([], 2, ["COMMAND"]),
    (["nonsense"], 2, ["invalid choice", "'demo'", "'run'"]),
]


@pytest.mark.parametrize(("argv", "code", "fragments"), BAD, ids=[" ".join(b[0]) or "(nothing)" for b in BAD])
def test_bad_input_is_one_clear_line(
    argv: list[str], code: int, fragments: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(argv) == code
    captured = capsys.readouterr()
    line = _one_error_line(captured.err)
    for fragment in fragments:
        assert fragment in line, line
    if code == 2:
        assert captured.out == ""


@pytest.mark.parametrize(
    ("argv", "code"),
    [
        (["run", "nosuch"], 2),
        (["run", "two-masses", "--param", "m1=-1"], 1),
        (["run", "two-masses", "--param", "m1=abc"], 2),
        (["run", "two-masses", "--solver", "magic"], 2),
        (["verify", "two-masses", "--method", "euler"], 2),
    ],
)
def test_bad_input_by_the_real_entry_point(argv: list[str], code: int) -> None:
    result = _command(*argv)
    assert result.returncode == code
    _one_error_line(result.stderr)


def test_help_everywhere(capsys: pytest.CaptureFixture[str]) -> None:
    for argv in (["run", "--help"], ["verify", "-h"], ["scenes", "--help"], ["report", "--help"], ["demo", "-h"]):
        assert cli.main(argv) == 0
        captured = capsys.readouterr()
        assert captured.out.startswith(f"usage: gausspp {argv[0]}") and captured.err == ""
    result = _command("--help")
    assert result.returncode == 0 and result.stdout.startswith("usage: gausspp") and result.stderr == ""
    assert "exit codes" in result.stdout and "gausspp verify two-masses" in result.stdout


def test_debug_shows_the_exception(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(gp.InputError, match="m1, m2 > 0"):
        cli.main(["--debug", "run", "two-masses", "--param", "m1=-1"])
    with pytest.raises(gp.InputError):  # after the subcommand too
        cli.main(["run", "two-masses", "--param", "m1=-1", "--debug"])
    result = _command("--debug", "run", "two-masses", "--param", "m1=-1")
    assert result.returncode == 1 and "Traceback" in result.stderr and "InputError" in result.stderr


def test_an_unforeseen_exception_is_still_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken() -> dict[str, str]:
        raise RuntimeError("something\nbroke")

    monkeypatch.setattr(gp.scenes, "describe", broken)
    assert cli.main(["scenes"]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "RuntimeError: something broke" in line and "--debug" in line


# -- pieces -------------------------------------------------------------------------------------------
def test_parameter_values_are_python_literals() -> None:
    assert params.parse_params("rigid-body-servo", ["n=(1, 0.2, 0)", "t_end=2", "l=1,1,0"]) == {
        "n": (1, 0.2, 0),
        "t_end": 2.0,
        "l": (1, 1, 0),
    }
    assert params.parse_params("rigid-body-servo", ["n=None"]) == {"n": None}
    assert params.parse_params("crane", ["accel=None", "g=9"]) == {"accel": None, "g": 9.0}
    assert params.parse_params("two-masses", ["realization=servo"]) == {"realization": "servo"}
    assert params.parse_params("two-masses", ["realization='servo'"]) == {"realization": "servo"}
    assert params.parse_params("stiff-chain", ["n=5", "stiff=(1, 2)"]) == {"n": 5, "stiff": (1, 2)}
    assert isinstance(params.parse_params("stiff-chain", ["n=5.0"])["n"], int)


def test_progress_on_a_non_terminal(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(console.Progress, "_LOG_AT", (0.05,))
    err = ""
    with console.Progress("working", delay=0.0):
        deadline = time.monotonic() + 60  # wait for the line, however loaded the machine (only a hang waits long)
        while "gausspp: working … " not in err and time.monotonic() < deadline:
            time.sleep(0.01)
            err += capsys.readouterr().err
    err += capsys.readouterr().err
    assert "gausspp: working … " in err and "gausspp: working: done in" in err
    with console.Progress("quick", delay=1.0):  # shorter than the delay: silent
        pass
    with console.Progress("muted", enabled=False, delay=0.0):
        time.sleep(0.1)
    assert capsys.readouterr().err == ""


def test_thin_drops_near_duplicate_nodes_and_keeps_the_end() -> None:
    scene = gp.scenes.get("two-masses")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0, method="DOP853", dt=1 / 400, rtol=1e-10, atol=1e-12)
    if np.diff(traj.t).min() > 1e-10:
        pytest.skip("this scipy does not end on a round-off step here")
    thinned = runs.thin(traj, 0.05 / 400)  # scipy ended on a step of round-off size: that node goes
    assert thinned.t[0] == 0.0 and thinned.t[-1] == 1.0 and np.diff(thinned.t).min() > 0.05 / 400
    assert thinned.t.size == traj.t.size - 1
    assert thinned.q.shape == (thinned.t.size, 2) and thinned.margin.size == thinned.t.size


def test_demo_reports_each_row_as_it_finishes(demo_run) -> None:
    """One progress line per row on stderr (`gausspp demo: k/N what (s)`), every row of the tables counted once."""
    plan = demo_plan.plan(demo.backends(), demo_run.out)
    lines = [line for line in demo_run.stderr.splitlines() if line.startswith("gausspp demo: ")]
    assert len(lines) == len(plan)
    assert sorted(int(line.split()[2].split("/")[0]) for line in lines) == list(range(1, len(plan) + 1))
    assert all(line.split()[2].endswith(f"/{len(plan)}") and line.endswith(" s)") for line in lines)
    for task in plan:
        assert sum(f" {task.table} {task.name} (" in line for line in lines) == 1, task


def test_the_run_summary_names_coordinates_with_units_and_shortens_long_vectors(capsys) -> None:
    """Issue 30, item 5: `gausspp run` names each coordinate with its unit (velocities as rates), explains the
    margin, and shows a 96-entry state by its first and last entries with the count."""
    from gausspp.cli import main

    assert main(["run", "pendulum", "--t-end", "0.2"]) == 0
    out = capsys.readouterr().out
    lines = {line.split()[0] + " " + line.split()[1]: line for line in out.splitlines() if line.startswith("  final")}
    assert "x = " in lines["final q"] and " m, " in lines["final q"] and " rad" in lines["final q"]
    assert "φ′ = " in lines["final v"] and "rad/s" in lines["final v"]
    assert "pin-x = " in lines["final u"]
    assert "1 = one ideal row" in out
    assert main(["run", "planar-chain", "-p", "N=32", "--t-end", "0.05"]) == 0
    out = capsys.readouterr().out
    final_q = next(line for line in out.splitlines() if line.startswith("  final q"))
    assert "(96 values)" in final_q and final_q.count(" = ") <= 8 and "θ₃₂ = " in final_q


def test_the_scene_list_shows_no_markup(capsys) -> None:
    """Issue 30, item 5: `gausspp scenes` and `gausspp scenes NAME` print text, not reST (``m1``, :func:`…`)."""
    assert cli.main(["scenes"]) == 0
    listing = capsys.readouterr().out
    assert "``" not in listing and ":func:" not in listing and "follower force on m1" in listing
    for name in gp.scenes.names():
        assert cli.main(["scenes", name]) == 0
        out = capsys.readouterr().out
        assert "``" not in out and ":func:`" not in out and ":data:`" not in out and ":class:`" not in out, name
