"""The documentation site builds with warnings as errors (``make docs``), here without the slow examples.

The build runs the gallery (every example not in ``SLOW_EXAMPLES`` of docs/conf.py) and writes the
site into a temporary directory (about 30 s from a fresh clone on a shared 2-core machine, so it runs by
default; the gallery's generated sources go to docs/auto_examples and docs/api, both ignored by git).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("sphinx")
pytest.importorskip("pydata_sphinx_theme")
pytest.importorskip("myst_parser")
pytest.importorskip("sphinx_gallery")
pytest.importorskip("matplotlib")
Image = pytest.importorskip("PIL.Image")

#: The examples whose gallery page plays an animation (issue 21: at least six).
ANIMATED = (
    "two_masses",
    "nonholonomic_vs_vakonomic",
    "crane_servo",
    "bouncing_block",
    "redundant_four_bar",
    "one_constraint_three_realizations",
    "friction",
)


def test_site_builds_without_warnings(tmp_path: Path) -> None:
    env = {**os.environ, "GAUSSPP_DOCS_SKIP_SLOW": "1", "MPLBACKEND": "Agg"}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    out = tmp_path / "html"
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html"]
    cmd += ["-d", str(tmp_path / "doctrees"), str(ROOT / "docs"), str(out)]
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-4000:]
    for page in ("index", "guide", "theory", "architecture", "api/index", "auto_examples/index"):
        assert (out / f"{page}.html").is_file(), page
    examples = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))
    for name in examples:  # every example has its page, its notebook and its script
        assert (out / "auto_examples" / f"{name}.html").is_file(), name
    notebooks = {p.stem for p in out.rglob("*.ipynb")}
    assert set(examples) <= notebooks
    # the fast examples ran: their figures were captured from matplotlib
    assert (out / "_images" / "sphx_glr_two_masses_001.png").is_file()
    # and the animated ones show their GIFs (written by plot.animate, several frames each) on their pages
    for name in ANIMATED:
        page = (out / "auto_examples" / f"{name}.html").read_text()
        gifs = re.findall(r'src="(\.\./_images/sphx_glr_[^"]+\.gif)"', page)
        assert gifs, f"{name}: no animation on its page"
        with Image.open(out / "auto_examples" / gifs[0]) as gif:
            assert gif.n_frames >= 30, name
    assert len(ANIMATED) >= 6


def test_api_reference_lists_every_public_name() -> None:
    import gausspp
    import gausspp.scenes

    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import conf  # docs/conf.py writes docs/api/index.rst from the packages' __all__
    finally:
        sys.path.remove(str(ROOT / "docs"))
    text = (conf.DOCS / "api" / "index.rst").read_text()
    entries = {line.strip() for line in text.splitlines() if line.startswith("   ") and ":" not in line}
    assert set(gausspp.__all__) | set(gausspp.scenes.__all__) <= entries
