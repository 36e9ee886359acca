"""Fixtures shared by the tests."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest


@pytest.fixture(scope="session", autouse=True)
def private_disk_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Compiled functions go to a directory of this test session (gausspp.disk_cache), never the user's cache."""
    from gausspp import disk_cache

    folder = tmp_path_factory.mktemp("gausspp-cache")
    os.environ[disk_cache.ENV] = str(folder)  # child processes (the demo's workers, the CLI) inherit it
    return folder


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


class DemoRun(NamedTuple):
    stdout: str
    stderr: str
    returncode: int
    out: Path
    #: stdout and stderr in one stream, in the order a terminal shows them (both unbuffered)
    merged: str


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> DemoRun:
    """`gausspp demo` by the real entry point, once per test session (it takes about a minute)."""
    out = tmp_path_factory.mktemp("demo")
    result = subprocess.run(
        [sys.executable, "-m", "gausspp.cli", "demo", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=900,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    merged = result.stdout
    progress = [line for line in merged.splitlines() if line.startswith("gausspp demo: ")]
    stdout = "\n".join(line for line in merged.splitlines() if not line.startswith("gausspp demo: ")) + "\n"
    return DemoRun(stdout, "\n".join(progress) + "\n", result.returncode, out, merged)
