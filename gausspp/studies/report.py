"""Error against run time (work-precision) and the QP error floor (DiffEqDevTools-style).

:func:`work_precision` runs the study of :mod:`gausspp.studies.work_precision` in this process (for
each scene, each method over a sweep of ``dt`` or ``rtol`` and each step solver, scored against the
exact solution or a finer reference by another method); :func:`table`, :func:`summary_lines` and
:func:`write` present its rows. Wall time is the minimum of several runs (these machines are shared
and noisy). Failed runs stay in the table.

:func:`qp_floor` measures each QP backend's step against the direct solution, and OSQP's floor
against its tolerances with and without polishing.
"""

from __future__ import annotations

import csv
import json
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from .. import scenes
from ..errors import GaussppError
from ..model.model import Model
from ..simulation.simulate import simulate
from ..step import qp
from ..step.qp import CasadiConic
from .work_precision import (
    HORIZON,
    STUDY_PARAMS,
    Reference,
    Row,
    describe,
    plan,
    reference,
    score,
    work_precision_task,
)

__all__ = [
    "HORIZON",
    "STUDY_PARAMS",
    "Reference",
    "Row",
    "best_per_scene",
    "qp_floor",
    "reference",
    "summary_lines",
    "table",
    "work_precision",
    "write",
]


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
    """Run the study in this process, one task after the other; see :mod:`gausspp.studies.work_precision`.

    ``solvers`` are ``"direct"`` and QP backend names; ``progress``, if given, is called with a line
    naming each task before it runs. :func:`gausspp.sweeps.work_precision` runs the same tasks on
    worker processes (the same rows; only the wall times differ).
    """
    params = plan(scene_names, method_names, solvers, quick, repeats, samples)
    results = []
    for p in params:
        if progress is not None:
            progress(describe(p))
        results.append(work_precision_task(p))
    return score(params, results, {})


def table(rows: Sequence[Row]) -> str:
    """A terminal table of the study."""
    head = (
        f"{'scene':18s} {'method':13s} {'solver':12s} {'setting':16s} {'final err':>9s} {'max err':>9s} "
        f"{'digits':>6s} {'|Φ|,|g|':>8s} {'energy':>8s} {'wall s':>8s} {'steps':>7s} {'rhs':>7s}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        if r.status == "failed":
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
        if r.status != "failed" and r.final_error <= target:
            best = out[r.scene]
            if best is None or r.wall_time < best.wall_time:
                out[r.scene] = r
    return out


def summary_lines(rows: Sequence[Row], target: float = 1e-10) -> list[str]:
    """The table, then the fastest run per scene reaching a final-state error of ``target``."""
    lines = [table(rows), f"\nFastest run reaching a final-state error ≤ {target:g}, per scene:"]
    for scene, row in best_per_scene(rows, target).items():
        shown = (
            "none"
            if row is None
            else f"{row.method} · {row.solver} · {row.setting}: {row.final_error:.1e} in {row.wall_time:.4f} s"
        )
        lines.append(f"  {scene:20s} {shown}")
    return lines


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
