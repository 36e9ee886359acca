"""Verification time against the number of nodes: ``python benchmarks/verify.py``.

For a scene with a differential relation (20) (the gyrostat, n = 3, a sparse QP with interval
rows) and one with pointwise relations (the pendulum, n = 3, two holonomic rows), time
``gp.verify`` (discretization, the QP on the nodes and on every other node for the verdict) at
several node counts, minimum of 3 runs; and a 6-mass chain (n = 6, pointwise rows).
Goal from issue 4: 1000 nodes, n ≤ 6, under 2 s.
"""

from __future__ import annotations

import time

import numpy as np

import gausspp as gp


def main() -> None:
    print(f"{'scene':12s} {'nodes':>6s} {'n':>3s} {'verify s':>9s} {'closed form s':>14s} {'relative gap':>13s}")
    cases = [("gyrostat", {}, 5.0), ("pendulum", {}, 2.0), ("stiff-chain", {"n": 6, "stiffness_ratio": 1e2}, 1.0)]
    for name, params, horizon in cases:
        scene = gp.scenes.get(name, **params)
        traj = gp.simulate(
            scene.model,
            scene.q0,
            scene.v0,
            horizon,
            lam0=scene.lam0,
            method="DOP853",
            rtol=1e-12,
            atol=1e-14,
            solver="direct",
            record=np.linspace(0, horizon, 4001),
        )
        for nodes in (250, 500, 1000, 2000):
            best, ver = np.inf, None
            for _ in range(3):
                start = time.perf_counter()
                ver = gp.verify(scene.model, traj, nodes=nodes)
                best = min(best, time.perf_counter() - start)
            closed = "—"
            if all(not c.realization.has_state for c in scene.model.constraints):
                start = time.perf_counter()
                gp.verify(scene.model, traj, nodes=nodes, method="closed-form")
                closed = f"{time.perf_counter() - start:.3f}"
            assert ver is not None
            print(f"{name:12s} {nodes:6d} {scene.model.nv:3d} {best:9.3f} {closed:>14s} {ver.relative_gap:13.2e}")
    print("goal: 1000 nodes, n ≤ 6, under 2 s")


if __name__ == "__main__":
    main()
