"""Contacts: error of the located impact times against the closed forms, against run time.

    .venv/bin/python benchmarks/contact.py

For each tolerance, the event-driven simulation of ``block-on-floor`` (ten bounces, closed-form
times) and ``bouncing-pendulum`` (elliptic-integral times): the largest impact-time error, the
apex-height error (block), the kinetic-energy ratio error at the impacts (pendulum) and the wall
time (best of three). Also the cost of one general Gauss QP step (the inequality QP deciding the
contacts) and of one impact QP, per backend.
"""

from __future__ import annotations

import time

import numpy as np

import gausspp as gp
from gausspp.scenes.block_on_floor import bounce_times
from gausspp.scenes.bouncing_pendulum import impact_times

G = 9.81


def best_of(fn, repeats: int = 3) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def impacts(traj: gp.Trajectory) -> np.ndarray:
    return np.array(sorted({ev["t"] for ev in traj.events if ev["kind"] == "impact"}))


def main() -> None:
    block = gp.scenes.get("block-on-floor", e=0.5, drop=1.0, t_end=1.5)
    pend = gp.scenes.get("bouncing-pendulum", e=0.8, theta0=1.0, t_end=3.5)
    print(
        f"{'rtol':>8s} | {'block: t err':>12s} {'events':>6s} {'wall ms':>8s} | {'pendulum: t err':>15s} "
        f"{'KE ratio err':>12s} {'wall ms':>8s}"
    )
    print("-" * 86)
    for rtol in (1e-6, 1e-8, 1e-10, 1e-12):
        atol = rtol * 1e-2
        wall_b, tb = best_of(lambda: gp.simulate(block.model, block.q0, block.v0, block.t_end, rtol=rtol, atol=atol))
        times = impacts(tb)
        err_b = float(np.max(np.abs(times[:10] - bounce_times(1.0, 0.5, G, 10))))
        wall_p, tp = best_of(lambda: gp.simulate(pend.model, pend.q0, pend.v0, pend.t_end, rtol=rtol, atol=atol))
        tpi = impacts(tp)
        err_p = float(np.max(np.abs(tpi - impact_times(1.0, G, 1.0, 0.8, tpi.size))))
        ratios = [
            ev["kinetic_energy_after"] / ev["kinetic_energy_before"] for ev in tp.events if ev["kind"] == "impact"
        ]
        err_ke = float(np.max(np.abs(np.array(ratios) - 0.64)))
        print(
            f"{rtol:8.0e} | {err_b:12.2e} {len(tb.events):6d} {wall_b * 1e3:8.1f} | {err_p:15.2e} {err_ke:12.2e} "
            f"{wall_p * 1e3:8.1f}"
        )
    print("\nOne general Gauss QP step (ball resting on the floor) and one impact QP, µs (best of 200):")
    model = block.model
    q = np.array([0.0, 0.1, 0.0])
    for backend in ("daqp", "osqp"):
        step_s, _ = best_of(lambda: [model.step(0.0, q, np.zeros(3), backend=backend) for _ in range(200)], 3)
        imp_s, _ = best_of(
            lambda: [model.impact(0.0, q, np.array([0.0, -1.0, 0.0]), backend=backend) for _ in range(200)], 3
        )
        print(f"  {backend:6s} step {step_s / 200 * 1e6:8.1f}   impact {imp_s / 200 * 1e6:8.1f}")


if __name__ == "__main__":
    main()
