"""Stiff spring chain: explicit RK4 at its stability limit against the stiff Radau method, on work."""

from __future__ import annotations

import math
import time

import numpy as np

from ... import scenes
from ...errors import GaussppError
from ...model.model import Model
from ...simulation.simulate import simulate
from ...simulation.trajectory import Trajectory
from .common import Case, fmt

NAME = "stiff chain"
WHAT = (
    "stiff-chain scene, stiffness ratio 1e8 (stiff frequency ω ≈ 1.4e4), lever constraint; explicit RK4 against "
    "the stiff Radau method (solver='direct', exact casadi Jacobian), final error vs the modal exact solution"
)
EXPECTED = (
    "Radau reaches a final error ≤ 1e-6 with at least 10× fewer right-hand-side evaluations than RK4 at the largest "
    "step at which RK4 reaches 1e-6 (RK4 is limited by its stability bound dt·ω ≤ 2√2)"
)


def _highest_frequency(model: Model) -> float:
    """ω_max of the linear chain ``q̈ = −L q`` (its step at ``v = 0`` is linear in ``q``)."""
    n = model.nv
    L = np.column_stack([-model.step(0.0, e, np.zeros(n), solver="direct").a for e in np.eye(n)])
    return float(np.sqrt(np.max(np.linalg.eigvals(L).real)))


class _Chain:
    """The stiff chain at one stiffness ratio, its exact end state, and runs judged against it."""

    def __init__(self, ratio: float, t_end: float) -> None:
        scene = scenes.get("stiff-chain", stiffness_ratio=ratio, t_end=t_end)
        assert scene.exact is not None
        self.model, self.q0, self.v0, self.t_end = scene.model, scene.q0, scene.v0, t_end
        self.qe, self.ve = scene.exact(t_end)
        self.reached: dict[int, bool] = {}

    def error(self, traj: Trajectory) -> float:
        if not traj.success:
            return math.inf
        return float(max(np.max(np.abs(traj.q[-1] - self.qe)), np.max(np.abs(traj.v[-1] - self.ve))))

    def rk4(self, n: int, lane: str = "compiled") -> Trajectory:
        return simulate(
            self.model,
            self.q0,
            self.v0,
            self.t_end,
            dt=self.t_end / n,
            method="rk4",
            lane=lane,
            solver="direct",
            record=n,
            throw=False,
        )

    def reaches(self, n: int, tol: float) -> bool:
        if n not in self.reached:
            self.reached[n] = self.error(self.rk4(n)) <= tol
        return self.reached[n]

    def largest_step(self, tol: float) -> tuple[int, int]:
        """``(lo, hi)``: RK4 with ``hi`` steps reaches ``tol``, with ``lo`` it does not (0: not searched below 8)."""
        n = 8
        while not self.reaches(n, tol):
            n *= 2
            if n > 2**24:
                raise GaussppError(f"RK4 did not reach {tol:g} with 2^24 steps")  # pragma: no cover
        lo, hi = (n // 2, n) if n > 8 else (0, n)
        while hi - lo > max(1, hi // 200):  # to 0.5 %
            mid = (lo + hi) // 2
            lo, hi = (lo, mid) if self.reaches(mid, tol) else (mid, hi)
        return lo, hi

    def adaptive(
        self, out: dict[str, float], key: str, method: str, rtol: float, atol: float, warm_up: bool = True
    ) -> None:
        """One adaptive run's wall time, steps, evaluations and error, into ``out`` under ``key``."""

        def once() -> Trajectory:
            return simulate(
                self.model,
                self.q0,
                self.v0,
                self.t_end,
                method=method,
                solver="direct",
                rtol=rtol,
                atol=atol,
                throw=False,
            )

        if warm_up:  # the exact Jacobian (Radau, BDF) and CVODES' graph are compiled on first use
            once()
        start = time.perf_counter()
        traj = once()
        out[f"{key}_wall_s"] = time.perf_counter() - start
        out[f"{key}_steps"] = float(traj.steps)
        out[f"{key}_evaluations"] = float(traj.rhs_evaluations)
        out[f"{key}_error"] = self.error(traj)


def _rk4_figures(chain: _Chain, ratio: float, tol: float) -> dict[str, float]:
    """RK4's largest step reaching ``tol``, and that step's work and wall time in both lanes."""
    lo, hi = chain.largest_step(tol)
    t_end, omega = chain.t_end, _highest_frequency(chain.model)
    out: dict[str, float] = {
        "stiffness_ratio": ratio,
        "t_end": t_end,
        "omega_max": omega,
        "rk4_steps": float(hi),
        "rk4_dt": t_end / hi,
        "rk4_dt_times_omega": t_end / hi * omega,
        "rk4_runs_in_search": float(len(chain.reached)),
    }
    if lo > 0:
        out["rk4_next_larger_dt"] = t_end / lo
        out["rk4_next_larger_dt_error"] = chain.error(chain.rk4(lo))
    # the same step in the Python lane (one step evaluation per stage): work and wall time
    start = time.perf_counter()
    py = chain.rk4(hi, "python")
    out["rk4_wall_s"] = time.perf_counter() - start
    out["rk4_evaluations"] = float(py.rhs_evaluations)
    out["rk4_error"] = chain.error(py)
    start = time.perf_counter()
    out["rk4_compiled_error"] = chain.error(chain.rk4(hi))
    out["rk4_compiled_wall_s"] = time.perf_counter() - start
    return out


def _contrast(ratio: float, t_end: float, tol: float = 1e-6, rk45: bool = False) -> dict[str, float]:
    """RK4 at its largest step reaching ``tol`` against Radau (BDF, cvodes and, if asked, RK45); numbers only."""
    chain = _Chain(ratio, t_end)
    out = _rk4_figures(chain, ratio, tol)
    chain.adaptive(out, "radau", "Radau", 1e-6, 1e-9)
    out["evaluation_ratio"] = out["rk4_evaluations"] / max(out["radau_evaluations"], 1.0)
    chain.adaptive(out, "bdf", "BDF", 1e-8, 1e-10)
    chain.adaptive(out, "cvodes", "cvodes", 1e-8, 1e-10)
    if rk45:  # an explicit adaptive method for contrast: its step is limited by stability, not accuracy
        chain.adaptive(out, "rk45", "RK45", 1e-8, 1e-10, warm_up=False)
    return out


def case(quick: bool = True) -> Case:
    """Stiff spring chain (ratio 1e8): RK4 at its stability limit against Radau, on work."""
    t_end = 1.0 if quick else 10.0
    f = _contrast(1e8, t_end, rk45=True)
    extra = ""
    if not quick:
        for ratio in (1e6, 1e10):
            g = _contrast(ratio, t_end)
            tag = f"{ratio:.0e}".replace("+", "")
            for key in ("rk4_steps", "rk4_evaluations", "radau_evaluations", "radau_error", "evaluation_ratio"):
                f[f"{key}@{tag}"] = g[key]
            extra += (
                f" At ratio {ratio:.0e}: RK4 {g['rk4_evaluations']:.0f} evaluations, Radau "
                f"{g['radau_evaluations']:.0f} (error {fmt(g['radau_error'])}), {g['evaluation_ratio']:.0f}×."
            )
    verdict = f["radau_error"] <= 1e-6 and f["rk4_error"] <= 1e-6 and f["evaluation_ratio"] >= 10.0
    observed = (
        f"Over t ∈ [0, {t_end:g}], ω_max = {f['omega_max']:.4g}: RK4 reaches 1e-6 only with dt ≤ {f['rk4_dt']:.4g} "
        f"(dt·ω = {f['rk4_dt_times_omega']:.2f}, its stability limit 2√2 ≈ 2.83; at dt = "
        f"{f.get('rk4_next_larger_dt', math.nan):.4g} the final error is "
        f"{fmt(f.get('rk4_next_larger_dt_error', math.nan))}): {f['rk4_steps']:.0f} steps, "
        f"{f['rk4_evaluations']:.0f} evaluations, error {fmt(f['rk4_error'])}. Radau (rtol 1e-6) takes "
        f"{f['radau_steps']:.0f} steps, {f['radau_evaluations']:.0f} evaluations (plus its Jacobians, not counted), "
        f"error {fmt(f['radau_error'])}: {f['evaluation_ratio']:.0f}× fewer. Wall: RK4 {f['rk4_wall_s']:.3f} s "
        f"(compiled lane {f['rk4_compiled_wall_s']:.3f} s), Radau {f['radau_wall_s']:.3f} s. For contrast: BDF "
        f"{f['bdf_evaluations']:.0f} evaluations (error {fmt(f['bdf_error'])}), cvodes {f['cvodes_evaluations']:.0f} "
        f"({fmt(f['cvodes_error'])}); the explicit adaptive RK45 at rtol 1e-8 needs {f['rk45_evaluations']:.0f} "
        f"and ends at {fmt(f['rk45_error'])}." + extra
    )
    return Case(NAME, WHAT, EXPECTED, observed, bool(verdict), f)
