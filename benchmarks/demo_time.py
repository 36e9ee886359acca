"""First-run wall time of ``gausspp demo`` against its 10 s target: ``python benchmarks/demo_time.py``.

Runs ``python -m gausspp.cli demo`` once in a fresh subprocess, in a fresh temporary directory that
is also its ``HOME`` (the figures go there; nothing from an earlier run is reused: gausspp keeps no
on-disk cache), and prints its wall and CPU time, the time of each row as the demo reports it on
stderr (``gausspp demo: k/N what (s)``; rows run side by side on worker processes, so their sum
exceeds the wall time), and the ratio to the target. One run only; on a shared machine the figure
varies with the other load.
"""

from __future__ import annotations

import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 10.0
ROW = re.compile(r"^gausspp demo: \d+/\d+ (.+) \(([\d.]+) s\)$", re.M)


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(
            os.environ,
            HOME=tmp,
            MPLBACKEND="Agg",
            MPLCONFIGDIR=str(Path(tmp) / "mpl"),
            PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
        )
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        result = subprocess.run(
            [sys.executable, "-m", "gausspp.cli", "demo"], cwd=tmp, env=env, capture_output=True, text=True
        )
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if result.returncode != 0:
        sys.stderr.write(result.stderr)
        raise SystemExit(f"gausspp demo failed with exit code {result.returncode}")
    rows = sorted(((float(s), what) for what, s in ROW.findall(result.stderr)), reverse=True)
    print("row times (s, longest first; on worker processes, side by side):")
    for seconds, what in rows:
        print(f"  {seconds:6.1f}  {what}")
    print(f"  {sum(s for s, _ in rows):6.1f}  sum of the rows")
    verdict = "within" if wall <= TARGET_S else "OVER"
    print(
        f"gausspp demo: {wall:.1f} s wall, {cpu:.1f} s CPU, on {os.cpu_count()} cores; "
        f"{wall / TARGET_S:.2f} × the {TARGET_S:g} s target ({verdict})"
    )


if __name__ == "__main__":
    main()
