"""The examples run and write their figures; the CLI answers (the README's own claims: test_readme.py)."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

from gausspp import cli
from gausspp.studies import demo, tables

ROOT = Path(__file__).resolve().parents[1]


#: What tests/test_docs_site.py needs to build the site (and so to run the examples in its gallery).
DOCS_TOOLCHAIN = ("sphinx", "pydata_sphinx_theme", "myst_parser", "sphinx_gallery", "matplotlib", "PIL")


def _examples_here() -> list[str]:
    """The examples this module runs: all of them, or, where the docs toolchain is installed, only those the
    site's test build does not execute (docs/conf.py's ``SLOW_EXAMPLES``). The build runs every other one, and
    a failing example fails it (sphinx-gallery's ``only_warn_on_example_error`` is off): none runs twice."""
    names = sorted(p.name for p in (ROOT / "examples").glob("*.py"))
    if not all(importlib.util.find_spec(name) for name in DOCS_TOOLCHAIN):
        return names
    slow = re.search(r"SLOW_EXAMPLES = \[(.*?)\]", (ROOT / "docs" / "conf.py").read_text(), re.S)
    assert slow is not None, "docs/conf.py has no SLOW_EXAMPLES list"
    skipped = set(re.findall(r'"([^"]+\.py)"', slow.group(1)))
    assert skipped <= set(names), skipped
    return sorted(skipped)


@pytest.mark.parametrize("script", _examples_here())
def test_example_runs(script: str, tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / script), str(tmp_path / "figure.png")],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip()
    for png in tmp_path.glob("*.png"):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 1000


def test_demo_table(demo_run) -> None:
    import gausspp as gp

    assert demo_run.returncode == 0, demo_run.merged
    out = demo_run.stdout
    first = out.split("Every scene")[0].splitlines()
    step_rows = [line for line in first if line.startswith(("two-masses", "rigid-body-servo"))]
    assert len(step_rows) == 8
    assert all(float(r.split()[-3]) < 1e-12 for r in step_rows if " qp " in r)  # QP vs direct, raw answers
    assert all(float(r.split()[-2]) < 1e-12 for r in step_rows)  # each route vs the independent reference
    scene_rows = {line.split()[0]: line.split() for line in out.split("verified by (23)")[1].splitlines()[3:] if line}
    for name in gp.scenes.names("equality"):  # every scene: QP ≡ direct along the run, and a motion by (23)
        row = scene_rows[name]
        assert row[-2] == "yes" and float(row[-6]) < 1e-12


def _tables(text: str) -> list[list[str]]:
    """Each table of the demo's output: its header, its dashes, its rows (to the first blank line)."""
    lines = text.splitlines()
    out = []
    for i, line in enumerate(lines):
        if line and set(line) == {"-"} and i > 0:
            end = next((j for j in range(i + 1, len(lines)) if not lines[j].strip()), len(lines))
            out.append(lines[i - 1 : end])
    return out


def test_demo_tables_are_whole_aligned_and_say_their_units(demo_run) -> None:
    """Issue 30, item 5: in the stream a terminal shows, no progress line falls inside a table; every row is as
    wide as its header's columns (no label pushes them out of line); units and a legend for every column."""
    assert demo_run.returncode == 0, demo_run.merged
    tables = _tables(demo_run.merged)
    assert len(tables) == 3
    for table in tables:
        header, _dashes, *rows = table
        assert rows and not any(r.startswith("gausspp demo: ") for r in rows), table
        assert all(len(r) == len(header) for r in rows), [r for r in rows if len(r) != len(header)]
    step, scene, general = (t[0] for t in tables)
    assert "acceleration (SI)" in step and "µs/step" in step
    assert "T (s)" in scene and "run ms" in scene and "T (s)" in general
    out = demo_run.stdout
    for legend in ("acceleration (SI): ", "multiplier: ", "T: the run's length", "energy bal.:", "run ms: ", "— : no"):
        assert legend in out, legend
    assert "(saturated-crane) it is" in out and "by design" in out  # its residual explained
    assert not any("{" in line for line in demo_run.stderr.splitlines())  # no raw dicts in the progress lines


def test_scenes_listing(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["scenes"]) == 0
    assert "two-masses" in capsys.readouterr().out


def test_cli_bad_usage_exits_2() -> None:
    result = subprocess.run([sys.executable, "-m", "gausspp.cli", "nonsense"], capture_output=True, text=True)
    assert result.returncode == 2 and "invalid choice" in result.stderr


@pytest.mark.parametrize("first", ["daqp", "osqp"])
def test_demo_says_which_qp_backends_it_compared(
    first: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """With daqp the general-QP table compares it with OSQP; without, it says so (not OSQP against itself)."""
    import qpsolvers

    import gausspp.scenes
    import gausspp.step.general

    if first not in qpsolvers.available_solvers:
        pytest.skip(f"{first} is not installed")
    names = gausspp.scenes.names
    monkeypatch.setattr(
        gausspp.scenes,
        "names",
        lambda category="all": ["two-actuator-servo"] if category == "general" else names(category),
    )
    monkeypatch.setattr(gausspp.step.general, "default_backend", lambda: first)
    which = demo.backends()
    print("\n".join(tables.general_lines(which, demo.general_rows(which))))
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("two-actuator-servo")).split()
    if first == "daqp":
        assert which.second in ("proxqp", "osqp")
        assert f"(daqp, compared with {which.second})" in out and f"daqp vs {which.second}" in out
        assert float(row[-5]) < 1e-8  # the two backends agree along the run
    else:
        assert "osqp vs osqp" not in out and "daqp not installed — `pip install daqp`" in out
        assert row[-5] == "—"
