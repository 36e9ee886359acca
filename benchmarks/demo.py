"""Wall time of ``gausspp demo``, the README's main job: ``python benchmarks/demo.py``.

Runs ``python -m gausspp.cli demo`` once in a fresh temporary directory (the figures go there)
and prints its wall and CPU time (the demo's own table gives each scene's run time).
One run only: the demo takes about a minute. A first run on a fresh machine is slower still
(Python compiles the package's bytecode and matplotlib builds its font cache); run it twice to
see both.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        result = subprocess.run([sys.executable, "-m", "gausspp.cli", "demo"], cwd=tmp, env=env, capture_output=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if result.returncode != 0:
        sys.stderr.write(result.stderr.decode(errors="replace"))
        raise SystemExit(f"gausspp demo failed with exit code {result.returncode}")
    print(f"gausspp demo: {wall:.1f} s wall, {cpu:.1f} s CPU, on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
