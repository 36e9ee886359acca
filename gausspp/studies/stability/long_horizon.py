"""Long horizon: 1e5 (1e6) RK4 steps on the pendulum, drift and energy with and without stabilization."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ... import scenes
from ...simulation.drift import Baumgarte
from ...simulation.simulate import simulate
from ...simulation.trajectory import Trajectory
from .common import Case, fmt

NAME = "long horizon"
WHAT = (
    "constrained pendulum (two holonomic pins), rk4 in the compiled lane with dt = 0.01 for 1e5 steps (1e6 full): "
    "no drift control, stabilize='project', and Baumgarte.critical(0.1)"
)
EXPECTED = (
    "projection keeps |g| and |Φ| ≤ 1e-12 throughout; the raw drift grows (≥ 10× from a tenth of the run to its "
    "end); Baumgarte keeps it ≥ 1000× below the raw drift; energy error with projection ≤ 1e-4·mgL (RK4's "
    "truncation, no instability)"
)


def case(quick: bool = True) -> Case:
    """1e5 (1e6) RK4 steps on the pendulum: drift and energy with and without stabilization."""
    n_steps = 10**5 if quick else 10**6
    dt = 0.01
    t_end = n_steps * dt
    scene = scenes.get("pendulum")
    mgl = float(scene.params["m"] * scene.params["g"] * scene.params["L"])
    runs: dict[str, Trajectory] = {}
    walls: dict[str, float] = {}
    stabilizations: dict[str, Any] = {"raw": None, "project": "project", "baumgarte": Baumgarte.critical(0.1)}
    for key, stab in stabilizations.items():
        start = time.perf_counter()
        runs[key] = simulate(
            scene.model,
            scene.q0,
            scene.v0,
            t_end,
            dt=dt,
            method="rk4",
            lane="compiled",
            solver="direct",
            stabilize=stab,
            record=n_steps // 100,
            drift_tol=1.0,  # the raw run is meant to drift: its growth is the figure
        )
        walls[key] = time.perf_counter() - start
    f: dict[str, float] = {"steps": float(runs["raw"].steps), "dt": dt, "t_end": t_end}
    for key, traj in runs.items():
        g = np.max(np.abs(traj.g), axis=1)
        f[f"{key}_max_g"] = float(g.max())
        f[f"{key}_max_Phi"] = float(np.max(np.abs(traj.residual)))
        f[f"{key}_energy_drift"] = float(np.max(np.abs(traj.energy - traj.energy[0])))
        f[f"{key}_energy_balance"] = float(np.max(np.abs(traj.energy_balance())))
        f[f"{key}_wall_s"] = walls[key]
        if key == "raw":
            tenth = int(np.argmin(np.abs(traj.t - 0.1 * t_end)))
            f["raw_g_at_tenth"] = float(g[tenth])
            f["raw_g_growth"] = float(g[-1] / max(g[tenth], 1e-300))
            f["raw_g_growth_exponent"] = float(np.log(f["raw_g_growth"]) / np.log(traj.t[-1] / traj.t[tenth]))
    f["project_max_residual"] = runs["project"].max_residual()
    verdict = (
        all(traj.steps == n_steps for traj in runs.values())
        and f["project_max_residual"] <= 1e-12
        and f["raw_g_growth"] >= 10.0
        and f["baumgarte_max_g"] <= 1e-3 * f["raw_max_g"]
        and f["project_energy_drift"] <= 1e-4 * mgl
    )
    observed = (
        f"{n_steps:.0e} steps of dt = {dt:g} (t ≤ {t_end:g}). Raw: |g| grows from {fmt(f['raw_g_at_tenth'])} at a "
        f"tenth of the run to {fmt(f['raw_max_g'])} ({f['raw_g_growth']:.0f}×, ∝ t^{f['raw_g_growth_exponent']:.2f}), "
        f"|Φ| ≤ {fmt(f['raw_max_Phi'])}, energy off by {fmt(f['raw_energy_drift'])} (the reaction works on the "
        f"drift; balance {fmt(f['raw_energy_balance'])}). Projection: |g|, |Φ| ≤ {fmt(f['project_max_residual'])}, "
        f"energy drift {fmt(f['project_energy_drift'])} (RK4 truncation; balance {fmt(f['project_energy_balance'])}, "
        f"the projection's own energy change is not in the work integrals). Baumgarte τ = 0.1: |g| ≤ "
        f"{fmt(f['baumgarte_max_g'])}, |Φ| ≤ {fmt(f['baumgarte_max_Phi'])}, energy drift "
        f"{fmt(f['baumgarte_energy_drift'])}, balance {fmt(f['baumgarte_energy_balance'])}. Wall: raw "
        f"{walls['raw']:.2f} s, projection {walls['project']:.2f} s, Baumgarte {walls['baumgarte']:.2f} s."
    )
    return Case(NAME, WHAT, EXPECTED, observed, bool(verdict), f)
