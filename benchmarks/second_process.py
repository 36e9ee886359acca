"""How soon a second process reaches its first step (issue 18): ``python benchmarks/second_process.py [--n 64]``.

Two fresh Python processes in turn, sharing one empty disk cache (``GAUSSPP_CACHE_DIR``, a temporary directory):
each builds the ``planar-chain`` scene of ``N`` links, makes one checked ``model.step``, then one
``gp.simulate(..., method="rk4", lane="compiled", dt=1e-3)`` of 1000 steps. Printed for each: the import of gausspp, the
model, the first step (model + first ``model.step``), and the first run — the first process compiles and stores,
the second loads (:mod:`gausspp.disk_cache`). The time to the first step is the issue's figure (target ≤ 0.5 s).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

CHILD = r"""
import json, sys, time
start = time.perf_counter()
import gausspp as gp
from gausspp import disk_cache
imported = time.perf_counter()
scene = gp.scenes.get("planar-chain", N=int(sys.argv[1]))
model = scene.model
built = time.perf_counter()
model.step(0.0, scene.q0, scene.v0, solver="direct")
stepped = time.perf_counter()
gp.simulate(model, scene.q0, scene.v0, 1.0, dt=1e-3, method="rk4", lane="compiled", solver="direct")
ran = time.perf_counter()
print(json.dumps(dict(import_s=imported - start, model_s=built - imported, first_step_s=stepped - imported,
                      first_run_s=ran - stepped, counts=disk_cache.counts)))
"""

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=64, help="links of the chain (default 64)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "GAUSSPP_CACHE_DIR": cache, "PYTHONPATH": str(ROOT)}
        print(f"planar-chain N = {args.n}, one disk cache shared by two fresh processes")
        print(f"{'process':10s} {'import s':>9s} {'model s':>8s} {'to first step s':>16s} {'first run s':>12s}  cache")
        for label in ("first", "second"):
            done = subprocess.run([sys.executable, "-c", CHILD, str(args.n)], env=env, capture_output=True, text=True)
            if done.returncode != 0:
                raise SystemExit(done.stderr)
            r = json.loads(done.stdout.strip().splitlines()[-1])
            print(
                f"{label:10s} {r['import_s']:9.2f} {r['model_s']:8.2f} {r['first_step_s']:16.2f} "
                f"{r['first_run_s']:12.2f}  {r['counts']}"
            )
        print("to first step: the model built and one model.step made (target ≤ 0.5 s in the second process)")


if __name__ == "__main__":
    main()
