"""The docs' browser check (docs/browser_check) on a site of two pages: it passes the good one and names the
problems of the bad one — an image that does not decode, a script error, a missing file. Skipped, with the
reason, where Node.js/npm or the npm packages are not available."""

from __future__ import annotations

import base64
import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RUN = ROOT / "docs" / "browser_check" / "run.py"
#: a 1×1 GIF, the smallest animation there is
GIF = base64.b64decode("R0lGODlhAQABAIAAAAAAAP///ywAAAAAAQABAAACAUwAOw==")


def _runner():  # the wrapper as a module (it lives with the docs, not in the package)
    spec = importlib.util.spec_from_file_location("browser_check_run", RUN)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


@pytest.fixture(scope="module")
def installed() -> None:
    reason = _runner().install()
    if reason is not None:
        pytest.skip(f"no headless browser here: {reason}")


def _site(folder: Path, bad: bool) -> Path:
    folder.mkdir()
    (folder / "anim.gif").write_bytes(GIF)
    (folder / "index.html").write_text('<html><body><p>good</p><img src="anim.gif"></body></html>')
    if bad:
        (folder / "broken.png").write_bytes(b"not a png at all")
        body = '<img src="broken.png"><img src="missing.gif"><script>undefinedFunction()</script>'
        (folder / "bad.html").write_text(f"<html><body>{body}</body></html>")
    return folder


def _check(site: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(RUN), str(site)], capture_output=True, text=True, timeout=600)


def test_a_good_site_passes(installed: None, tmp_path: Path) -> None:
    done = _check(_site(tmp_path / "good", bad=False))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 pages, 1 images, 0 with problems" in done.stdout


def test_a_broken_page_is_named_with_its_problems(installed: None, tmp_path: Path) -> None:
    done = _check(_site(tmp_path / "bad", bad=True))
    assert done.returncode == 1, done.stdout + done.stderr
    report = done.stdout
    assert "bad.html:" in report and "index.html:" not in report
    assert "image not decoded" in report and "broken.png" in report
    assert "HTTP 404" in report and "missing.gif" in report
    assert "page error" in report and "undefinedFunction" in report
    assert "2 pages, 3 images, 1 with problems" in report


def test_without_a_site_it_says_what_to_do(tmp_path: Path) -> None:
    done = _check(tmp_path)
    assert done.returncode == 2 and "make docs" in done.stderr
