"""Wall time and steps of every scene × method × step solver, in one run: ``python benchmarks/simulate.py``.

For each scene: ``gp.simulate`` over the scene's horizon (capped by ``--horizon``) with the
fixed-step methods at one ``dt`` and the adaptive ones at one tolerance, both step solvers
(direct and the default QP backend). Columns: wall time (minimum of ``--repeats`` runs, set-up
included), accepted steps, right-hand-side evaluations, µs per step, and the final-state error
against the scene's exact solution where it has one. Failures stay in the table.

Then the compiled lane's per-step cost on the pendulum scene, timed on the ``mapaccum`` call
alone (the set-up is paid once per run; ``--compiled-only`` prints just this): the targets of
issue 3 are ≤ 8 µs per RK4 step with the QP (MuJoCo's RK4 step on the same pendulum takes
8.4 µs with soft constraints) and ≤ 2 µs on the direct path.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import gausspp as gp
from gausspp.simulation import lanes, methods
from gausspp.simulation.compiled import rhs_function, rk_step_function
from gausspp.simulation.drift import Stabilization

RUNS = [
    ("rk4", {"dt": 1e-3, "lane": "python"}),
    ("rk4", {"dt": 1e-3, "lane": "compiled"}),
    ("DOP853", {"rtol": 1e-10, "atol": 1e-12}),
    ("Radau", {"rtol": 1e-8, "atol": 1e-10}),
    ("cvodes", {"rtol": 1e-10, "atol": 1e-12}),
]


def best_of(repeats: int, fn):  # type: ignore[no-untyped-def]
    best, result = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def scene_table(horizon: float, repeats: int) -> None:
    print(
        f"{'scene':20s} {'method':13s} {'solver':12s} {'wall s':>8s} {'steps':>7s} {'rhs':>7s} "
        f"{'µs/step':>8s} {'error':>9s}"
    )
    print("-" * 90)
    for name in gp.scenes.names("equality"):
        scene = gp.scenes.get(name)
        t_end = min(scene.t_end, horizon)
        for method, opts in RUNS:
            for solver in ("direct", "qp"):
                label = f"{method} {opts['lane']}" if "lane" in opts else method
                if not lanes.accepts(methods.get(method), solver, lane=opts.get("lane")):
                    continue  # e.g. CVODES differentiates the right-hand side: direct path only
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        wall, traj = best_of(
                            repeats,
                            lambda: gp.simulate(
                                scene.model,
                                scene.q0,
                                scene.v0,
                                t_end,
                                lam0=scene.lam0,
                                method=method,
                                solver=solver,
                                record=100 if not methods.get(method).adaptive else 1,
                                **opts,
                            ),
                        )
                    err = "—"
                    if scene.exact is not None:
                        q, v = scene.exact(traj.t[-1])
                        err = f"{max(np.abs(traj.q[-1] - q).max(), np.abs(traj.v[-1] - v).max()):.1e}"
                    print(
                        f"{name:20s} {label:13s} {traj.solver:12s} {wall:8.3f} {traj.steps:7d} "
                        f"{traj.rhs_evaluations:7d} {wall / max(traj.steps, 1) * 1e6:8.1f} {err:>9s}"
                    )
                except gp.GaussppError as exc:
                    print(f"{name:20s} {label:13s} {solver:12s} FAILED: {exc}")


def compiled_step_cost(steps: int = 20_000) -> None:
    scene = gp.scenes.get("pendulum")
    print(f"\ncompiled lane, pendulum, one mapaccum call of {steps} RK4 steps (minimum of 5):")
    for solver, target in (("direct", 2.0), ("qp", 8.0)):
        F = rhs_function(scene.model, solver, None)
        run = rk_step_function(scene.model, F, methods.RK4, Stabilization()).mapaccum("run", steps)
        y0 = np.concatenate([scene.q0, scene.v0, np.zeros(scene.model.n_lam), [0.0, 0.0]])
        t, h = (np.arange(steps) * 1e-4)[None, :], np.full((1, steps), 1e-4)
        per_step = best_of(5, lambda: run(y0, t, h, np.zeros(2)))[0] / steps * 1e6
        label = "direct" if solver == "direct" else gp.qp.DEFAULT
        print(
            f"  {label:12s} {per_step:6.2f} µs per RK4 step   "
            f"target ≤ {target:g} µs: {'met' if per_step <= target else 'NOT met'}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--horizon", type=float, default=2.0, help="cap on each scene's t_end")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--compiled-only", action="store_true", help="only the compiled lane's µs per RK4 step (a few seconds)"
    )
    args = parser.parse_args()
    if not args.compiled_only:
        scene_table(args.horizon, args.repeats)
    compiled_step_cost()


if __name__ == "__main__":
    main()
