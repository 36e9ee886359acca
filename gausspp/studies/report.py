"""Error against run time (work-precision) and the QP error floor (issue 5; DiffEqDevTools-style).

:func:`work_precision` runs, for each scene, each method over a sweep (fixed-step methods over
``dt``, adaptive ones over ``rtol``) and each step solver, records the state at common sample
times, and scores it against the scene's exact solution — or, where a scene has none, against
a reference by a different method at a much finer setting (compiled RK4 with ≈1.6·10⁵ steps,
cross-checked by DOP853 at ``rtol = 1e-13``; the row says which). Errors are mixed
absolute/relative, ``max |x − x_ref| / max(1, |x_ref|)`` over ``q`` and ``v``, and are also
given as significant correct digits ``−log₁₀`` (the Bari test set's scoring). Wall time is the
minimum of several runs (these machines are shared and noisy). Failed runs stay in the table.

:func:`qp_floor` measures each QP backend's step against the direct solution, and OSQP's floor
against its tolerances with and without polishing.
"""

from __future__ import annotations

import csv
import json
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import scenes
from ..errors import GaussppError
from ..model.model import Model
from ..simulation import methods as _methods
from ..simulation.simulate import simulate
from ..step import qp
from ..step.qp import CasadiConic

#: Horizon cap (the long-horizon behaviour is the stability study's business).
HORIZON = 1.0

#: Scene parameters for the study where the defaults are too easy (a polynomial exact motion).
STUDY_PARAMS: dict[str, dict[str, Any]] = {"two-masses": {"realization": "servo", "k": 3.0, "v": 0.5}}


@dataclass(frozen=True)
class Row:
    """One run of the study."""

    scene: str
    method: str
    solver: str
    setting: str
    final_error: float
    max_error: float
    digits: float
    reference: str
    constraint_residual: float
    energy_error: float
    wall_time: float
    steps: int
    rhs_evaluations: int
    status: str
    message: str


@dataclass(frozen=True)
class Reference:
    """The states a run is scored against, at the common sample times."""

    t: np.ndarray
    x: np.ndarray
    source: str


def _mixed_error(x: np.ndarray, ref: np.ndarray) -> np.ndarray:
    return np.max(np.abs(x - ref) / np.maximum(1.0, np.abs(ref)), axis=-1)


def reference(scene: scenes.Scene, t: np.ndarray) -> Reference:
    """The exact solution, or compiled RK4 with ≈1.6·10⁵ steps checked against DOP853 at rtol 1e-13."""
    if scene.exact is not None:
        return Reference(t, np.array([np.concatenate(scene.exact(ti)) for ti in t]), "exact")
    T = float(t[-1])
    steps = (t.size - 1) * 2**13  # ≈ 1.6·10⁵ steps, the samples on the grid
    fine = simulate(
        scene.model,
        scene.q0,
        scene.v0,
        T,
        lam0=scene.lam0,
        method="rk4-compiled",
        dt=T / steps,
        solver="direct",
        record=t,
    )
    check = simulate(
        scene.model,
        scene.q0,
        scene.v0,
        T,
        lam0=scene.lam0,
        method="DOP853",
        rtol=1e-13,
        atol=1e-15,
        solver="direct",
        record=t,
    )
    x = np.hstack([fine.q, fine.v])
    spread = float(_mixed_error(np.hstack([check.q, check.v]), x).max())
    return Reference(t, x, f"rk4-compiled {steps} steps (DOP853 1e-13 agrees to {spread:.0e})")


def _settings(method: _methods.Method, T: float, samples: int, quick: bool) -> list[tuple[str, dict[str, Any]]]:
    if method.adaptive:
        tols = [1e-4, 1e-7, 1e-10, 1e-13] if quick else [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13]
        return [(f"rtol={r:g}", {"rtol": r, "atol": r * 1e-2}) for r in tols]
    base = T / (samples - 1)  # dt divides the sampling interval, so the samples lie on the grid
    factors = [4, 32, 256] if quick else [1, 4, 16, 64, 256, 1024]
    if method.lane == "python":
        factors = factors[:2]  # one Python call per stage: the fine end belongs to the compiled lane
    return [(f"dt=T/{(samples - 1) * f}", {"dt": base / f}) for f in factors]


def _best_of(repeats: int, run: Callable[[], Any]) -> tuple[float, Any]:
    best, result = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        best = min(best, time.perf_counter() - start)
    return best, result


def work_precision(
    scene_names: Sequence[str] | None = None,
    method_names: Sequence[str] | None = None,
    solvers: Sequence[str] | None = None,
    *,
    quick: bool = True,
    repeats: int = 2,
    samples: int = 21,
    progress: Callable[[str], None] | None = None,
) -> list[Row]:
    """Run the study; see the module docstring. ``solvers`` are ``"direct"`` and QP backend names."""
    names = list(scene_names or scenes.names("equality"))
    meths = [_methods.get(m) for m in (method_names or ["rk4", "rk4-compiled", "DOP853", "Radau", "cvodes"])]
    solver_list = list(solvers or ["direct", qp.DEFAULT, "casadi:osqp"])
    rows: list[Row] = []
    for name in names:
        scene = scenes.get(name, **STUDY_PARAMS.get(name, {}))
        T = min(scene.t_end, HORIZON)
        t = np.linspace(0.0, T, samples)
        ref = reference(scene, t)
        for meth in meths:
            for solver in solver_list:
                if meth.name == "cvodes" and solver != "direct":
                    continue  # CVODES differentiates the right-hand side: direct path only
                if progress:
                    progress(f"{name}: {meth.name} with {solver}")
                for setting, opts in _settings(meth, T, samples, quick):
                    rows.append(_one(scene, name, meth, solver, setting, opts, t, ref, repeats))
    return rows


def _one(
    scene: scenes.Scene,
    name: str,
    meth: _methods.Method,
    solver: str,
    setting: str,
    opts: dict[str, Any],
    t: np.ndarray,
    ref: Reference,
    repeats: int,
) -> Row:
    kind: dict[str, Any] = {"solver": "direct"} if solver == "direct" else {"solver": "qp", "backend": solver}
    nan = float("nan")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            wall, traj = _best_of(
                repeats,
                lambda: simulate(
                    scene.model,
                    scene.q0,
                    scene.v0,
                    float(t[-1]),
                    lam0=scene.lam0,
                    method=meth.name,
                    record=t,
                    **kind,
                    **opts,
                ),
            )
    except GaussppError as exc:
        return Row(
            name,
            meth.name,
            solver,
            setting,
            nan,
            nan,
            nan,
            ref.source,
            nan,
            nan,
            nan,
            0,
            0,
            "failed",
            f"{type(exc).__name__}: {exc}",
        )
    err = _mixed_error(np.hstack([traj.q, traj.v]), ref.x)
    final = float(err[-1])
    energy = float(np.nanmax(np.abs(traj.energy_balance()))) if np.isfinite(traj.energy_balance()).any() else nan
    return Row(
        name,
        meth.name,
        traj.solver,
        setting,
        final,
        float(err.max()),
        float(-np.log10(max(final, 1e-17))),
        ref.source,
        traj.max_residual(),
        energy,
        wall,
        traj.steps,
        traj.rhs_evaluations,
        traj.status,
        traj.message,
    )


def table(rows: Sequence[Row]) -> str:
    """A terminal table of the study."""
    head = (
        f"{'scene':18s} {'method':13s} {'solver':12s} {'setting':16s} {'final err':>9s} {'max err':>9s} "
        f"{'digits':>6s} {'|Φ|,|g|':>8s} {'energy':>8s} {'wall s':>8s} {'steps':>7s} {'rhs':>7s}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        if r.status != "success":
            lines.append(f"{r.scene:18s} {r.method:13s} {r.solver:12s} {r.setting:16s} FAILED: {r.message[:60]}")
            continue
        lines.append(
            f"{r.scene:18s} {r.method:13s} {r.solver:12s} {r.setting:16s} {r.final_error:9.1e} {r.max_error:9.1e} "
            f"{r.digits:6.1f} {r.constraint_residual:8.1e} {r.energy_error:8.1e} {r.wall_time:8.4f} {r.steps:7d} "
            f"{r.rhs_evaluations:7d}"
        )
    return "\n".join(lines)


def best_per_scene(rows: Sequence[Row], target: float = 1e-10) -> dict[str, Row | None]:
    """For each scene, the fastest run reaching ``target`` final error (``None`` if none did)."""
    out: dict[str, Row | None] = {}
    for r in rows:
        out.setdefault(r.scene, None)
        if r.status == "success" and r.final_error <= target:
            best = out[r.scene]
            if best is None or r.wall_time < best.wall_time:
                out[r.scene] = r
    return out


def write(rows: Sequence[Row], out: Path) -> list[Path]:
    """CSV and JSON of the study in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    records = [asdict(r) for r in rows]
    csv_path, json_path = out / "work_precision.csv", out / "work_precision.json"
    with csv_path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(records[0]) if records else [])
        writer.writeheader()
        writer.writerows(records)
    json_path.write_text(json.dumps(records, indent=1, default=float))
    return [csv_path, json_path]


def qp_floor(scene_names: Sequence[str] | None = None, samples: int = 5) -> dict[str, Any]:
    """Each backend's step against the direct solution at states along each scene's motion, and
    OSQP's own floor (without the refinement step) against ``eps_abs = eps_rel`` with and
    without polishing (on the pendulum)."""
    names = list(scene_names or scenes.names("equality"))
    worst: dict[str, float] = {}
    for name in names:
        scene = scenes.get(name)
        T = min(scene.t_end, HORIZON)
        traj = simulate(
            scene.model,
            scene.q0,
            scene.v0,
            T,
            lam0=scene.lam0,
            method="DOP853",
            solver="direct",
            rtol=1e-10,
            atol=1e-12,
            record=np.linspace(0, T, samples),
        )
        for i in range(len(traj)):
            args = (traj.t[i], traj.q[i], traj.v[i], traj.lam[i] if scene.model.n_lam else None)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                direct = scene.model.step(*args, solver="direct")
                for backend in qp.names():
                    try:
                        d = scene.model.step(*args, backend=backend).disagreement(direct)
                    except GaussppError:
                        d = float("inf")
                    worst[backend] = max(worst.get(backend, 0.0), d)
    osqp: dict[str, float] = {}
    pend = scenes.get("pendulum")
    raw = Model(pend.model.mechanism, pend.model.constraints, refine=False)  # the solver's own answer
    state = (0.3, pend.q0, pend.v0)
    direct = raw.step(*state, solver="direct")
    for eps in (1e-3, 1e-6, 1e-9, 1e-12):
        for polish in (False, True):
            label = f"osqp eps={eps:g} polish={'on' if polish else 'off'}"
            tuned = CasadiConic(
                "osqp",
                {"osqp": {"verbose": False, "eps_abs": eps, "eps_rel": eps, "polishing": polish}},
                name=f"casadi:{label.replace(' ', ',')}",
            )
            try:
                osqp[label] = raw.step(*state, backend=tuned).disagreement(direct)
            except GaussppError:
                osqp[label] = float("inf")
    return {"backends": worst, "osqp": osqp, "round_off": sorted(b for b, d in worst.items() if d <= 1e-13)}
