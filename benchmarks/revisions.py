"""The user's calls timed on two revisions side by side: ``python benchmarks/revisions.py [--before REV] [--rounds N]``.

Extracts ``REV`` (default ``cb68f0f``, main before the layout redesign of issue 16) with ``git archive`` into a
temporary directory, then times the same public calls — ``model.step`` (compiled direct and QP, the general QP
with bounds, contacts and redundant rows), ``gp.simulate`` (Python and compiled RK4, DOP853, an event-driven
contact run) and ``gp.verify`` — in child processes that import one revision or the other, alternating
``before, after, before, after, …`` for ``--rounds`` rounds so that the machine's load falls on both alike.
Each figure is the minimum over the rounds of the mean time per call; the last column is after / before.
Only public names are used, so the same code runs against both revisions.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import gausspp as gp

def per_call(fn, budget=0.3):
    fn()
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < budget:
        fn(); n += 1
    return (time.perf_counter() - start) / n

def step(name, solver="qp", **params):
    sc = gp.scenes.get(name, **params)
    return lambda: sc.model.step(0.0, sc.q0, sc.v0, solver=solver)

def run(name, t_end, **kw):
    sc = gp.scenes.get(name)
    return lambda: gp.simulate(sc.model, sc.q0, sc.v0, t_end, **kw)

def verify():
    sc = gp.scenes.get("pendulum")
    traj = gp.simulate(sc.model, sc.q0, sc.v0, 0.5, dt=1e-2, method="rk4")
    return lambda: gp.verify(sc.model, traj)

CALLS = {
    "model.step pendulum direct": step("pendulum", "direct"),
    "model.step pendulum qp": step("pendulum"),
    "model.step two-masses servo qp": step("two-masses", realization="servo"),
    "model.step saturated-crane (bounds)": step("saturated-crane"),
    "model.step block-on-floor (contacts)": step("block-on-floor"),
    "model.step four-bar-redundant": step("four-bar-redundant"),
    "simulate pendulum rk4 direct 1 s": run("pendulum", 1.0, dt=1e-3, method="rk4", solver="direct"),
    "simulate pendulum rk4 qp 1 s": run("pendulum", 1.0, dt=1e-3, method="rk4", solver="qp"),
    "simulate pendulum rk4 compiled direct 1 s": run("pendulum", 1.0, dt=1e-3, lane="compiled", solver="direct"),
    "simulate pendulum rk4 compiled qp 1 s": run("pendulum", 1.0, dt=1e-3, lane="compiled", solver="qp"),
    "simulate pendulum DOP853 1 s": run("pendulum", 1.0, method="DOP853", rtol=1e-10, atol=1e-10),
    "simulate block-on-floor 0.5 s (events)": run("block-on-floor", 0.5),
    "verify pendulum 0.5 s": verify(),
}
print(json.dumps({k: per_call(f) for k, f in CALLS.items()}))
"""


def extract(rev: str, into: Path) -> Path:
    """The revision's files (``git archive``) under ``into``; returns the tree's root."""
    data = subprocess.run(["git", "archive", rev], cwd=REPO, capture_output=True, check=True).stdout
    with tarfile.open(fileobj=BytesIO(data)) as tar:
        tar.extractall(into, filter="data")
    return into


def measure(root: Path) -> dict[str, float]:
    env = {**os.environ, "PYTHONPATH": str(root), "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True, cwd=root)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", default="cb68f0f", help="git revision to compare against (default: %(default)s)")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        before_root = extract(args.before, Path(tmp))
        best: dict[str, dict[str, float]] = {"before": {}, "after": {}}
        for _ in range(args.rounds):
            for label, root in (("before", before_root), ("after", REPO)):
                for name, sec in measure(root).items():
                    best[label][name] = min(sec, best[label].get(name, float("inf")))
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True).stdout
    print(f"before = {args.before}, after = {head.strip()} (working tree); min over {args.rounds} alternating rounds")
    print(f"{'call':45s} {'before':>12s} {'after':>12s} {'after/before':>13s}")
    for name, before in best["before"].items():
        after = best["after"][name]
        print(f"{name:45s} {before * 1e3:10.3f}ms {after * 1e3:10.3f}ms {after / before:13.2f}")


if __name__ == "__main__":
    main()
