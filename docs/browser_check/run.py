"""Open every page of the built site in a real headless browser: ``python docs/browser_check/run.py SITE_DIR``.

``make docs`` runs it after the build. It installs (once, into ``docs/browser_check/node_modules``) the two npm
packages of ``package.json`` — ``puppeteer-core`` and ``@sparticuz/chromium``, which ships a Chromium inside
itself and needs no other download — and runs ``check.mjs``: every page is served over a local HTTP server and
loaded; a console error, a page error, a failed request, or an image or animation that does not decode is a
problem, printed with its page. Exit code 1 when any page has one. Where Node.js and npm are missing, or the
packages cannot be installed (no network), it says so and exits 0: the check is skipped, not failed.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: npm install and one page load each get this long before the check gives up.
INSTALL_TIMEOUT, CHECK_TIMEOUT = 600, 1800


def install() -> str | None:
    """Install the packages if they are not there yet; the reason the check cannot run, or ``None``."""
    if not (shutil.which("node") and shutil.which("npm")):
        return "Node.js and npm were not found (install them to open the site in a headless browser)"
    stamp = HERE / "node_modules" / ".installed"
    if stamp.exists() and stamp.stat().st_mtime >= (HERE / "package.json").stat().st_mtime:
        return None
    command = ["npm", "install", "--no-audit", "--no-fund", "--loglevel=error"]
    try:
        done = subprocess.run(command, cwd=HERE, capture_output=True, text=True, timeout=INSTALL_TIMEOUT)
    except subprocess.TimeoutExpired:
        return f"npm install took longer than {INSTALL_TIMEOUT} s"
    if done.returncode:
        last = (done.stderr.strip().splitlines() or ["(no message)"])[-1]
        return f"npm install of puppeteer-core and @sparticuz/chromium failed: {last}"
    stamp.touch()
    return None


def main(argv: list[str]) -> int:
    site = Path(argv[0] if argv else "docs/_build/html").resolve()
    if not (site / "index.html").exists():
        print(f"browser check: no built site at {site} (run `make docs` first)", file=sys.stderr)
        return 2
    reason = install()
    if reason is not None:
        print(f"browser check skipped: {reason}")
        return 0
    try:
        return subprocess.run(["node", str(HERE / "check.mjs"), str(site)], cwd=HERE, timeout=CHECK_TIMEOUT).returncode
    except subprocess.TimeoutExpired:
        print(f"browser check: the pages took longer than {CHECK_TIMEOUT} s to load", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
