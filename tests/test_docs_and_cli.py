"""The README example runs; the examples run and write their figures; the CLI answers."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from gausspp import cli

ROOT = Path(__file__).resolve().parents[1]


def test_readme_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    text = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S)
    assert code is not None
    exec(compile(code.group(1), "README.md", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("rod [0.5 0.5]") and out[1].startswith("servo [0.66666667 0.66666667]")


@pytest.mark.parametrize("script", sorted(p.name for p in (ROOT / "examples").glob("*.py")))
def test_example_runs(script: str, tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / script), str(tmp_path / "figure.png")],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip()
    for png in tmp_path.glob("*.png"):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 1000


def test_demo_table(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    import gausspp as gp

    assert cli.main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    first = out.split("Every scene")[0].splitlines()
    step_rows = [line for line in first if line.startswith(("two-masses", "rigid-body-servo"))]
    assert len(step_rows) == 8
    assert all(float(r.split()[-2]) < 1e-12 for r in step_rows if " qp " in r)  # QP vs direct column
    scene_rows = {line.split()[0]: line.split() for line in out.split("verified by (23)")[1].splitlines()[3:] if line}
    for name in gp.scenes.names("equality"):  # every scene: QP ≡ direct along the run, and a motion by (23)
        row = scene_rows[name]
        assert row[-2] == "yes" and float(row[-6]) < 1e-12


def test_scenes_listing(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["scenes"]) == 0
    assert "two-masses" in capsys.readouterr().out


def test_cli_bad_usage_exits_2() -> None:
    result = subprocess.run([sys.executable, "-m", "gausspp.cli", "nonsense"], capture_output=True, text=True)
    assert result.returncode == 2 and "invalid choice" in result.stderr


def test_readme_simulation_snippet_runs() -> None:
    import gausspp as gp

    text = (ROOT / "README.md").read_text()
    blocks = [b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "gyrostat" in b]
    assert len(blocks) == 1
    namespace: dict[str, object] = {"gp": gp}
    exec(compile(blocks[0], "README.md", "exec"), namespace)
    traj = namespace["traj"]
    assert traj.success and abs(traj.energy_balance()).max() < 1e-11  # type: ignore[attr-defined]


def test_readme_contact_snippet_runs_and_says_what_it_computes() -> None:
    import gausspp as gp

    text = (ROOT / "README.md").read_text()
    blocks = [b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "gp.Unilateral" in b]
    assert len(blocks) == 1
    namespace: dict[str, object] = {"gp": gp}
    exec(compile(blocks[0], "README.md", "exec"), namespace)
    traj = namespace["traj"]
    impacts = [ev["t"] for ev in traj.events if ev["kind"] == "impact"][:3]  # type: ignore[attr-defined]
    t1 = (2 / 9.81) ** 0.5
    assert impacts == pytest.approx([t1, t1 * 2, t1 * 2.5], abs=1e-12)  # the times the comment quotes
    assert [f"{t:.4f}" for t in impacts] == ["0.4515", "0.9030", "1.1288"]
    assert traj.contact_force[-1] == pytest.approx([9.81], rel=1e-12)  # type: ignore[attr-defined]
