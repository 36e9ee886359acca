"""Command line: ``gausspp demo`` (the main job) and ``gausspp scenes``.

Errors print as one line (the traceback only with ``--debug``); exit codes: 0 success,
1 a gausspp error, 2 bad usage.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from . import qp, scenes
from .errors import GaussppError
from .model import Model


def _time_per_step(model: Model, t: float, q: np.ndarray, v: np.ndarray, lam: np.ndarray, solver: str) -> float:
    """Minimum over repeats of the compiled kernel's time per step, in µs."""
    kernel = model.kernel(solver)
    kernel.inputs[0][0] = t
    kernel.inputs[1][:], kernel.inputs[2][:], kernel.inputs[3][:] = q, v, lam
    calls, best = 2000, np.inf
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(calls):
            kernel.evaluate()
        best = min(best, (time.perf_counter() - start) / calls)
    return best * 1e6


def demo(args: argparse.Namespace) -> int:
    """Two masses, rod vs servo, and the rigid-body servo: QP vs direct, table and timings."""
    cases: list[tuple[str, dict[str, Any]]] = [
        ("two-masses", {"realization": "ideal"}),
        ("two-masses", {"realization": "servo"}),
        ("rigid-body-servo", {}),
        ("rigid-body-servo", {"n": (1.0, 0.2, 0.0)}),
    ]
    print(f"gausspp demo — one step at t = 0 by the direct formula and by the Gauss QP ({qp.DEFAULT})\n")
    header = (
        f"{'scene':18s} {'realization':22s} {'solver':8s} {'acceleration':>30s} "
        f"{'multiplier':>11s} {'QP vs direct':>12s} {'µs/step':>8s}"
    )
    print(header)
    print("-" * len(header))
    for name, params in cases:
        scene = scenes.get(name, **params)
        model = scene.model
        lam = scene.lam0 if scene.lam0 is not None else np.zeros(0)
        direct = model.step(0.0, scene.q0, scene.v0, solver="direct")
        gauss = model.step(0.0, scene.q0, scene.v0, solver="qp")
        label = params.get("realization") or (
            "Suslov (n = l)"
            if scene.params.get("suslov")
            else "servo n=(" + ", ".join(f"{x:.2f}" for x in scene.params["n"]) + ")"
        )
        for res, solver in ((direct, "direct"), (gauss, "qp")):
            acc = np.array2string(res.a, precision=5, suppress_small=True, separator=", ")
            gap = "" if solver == "direct" else f"{gauss.disagreement(direct):.1e}"
            us = _time_per_step(model, 0.0, scene.q0, scene.v0, lam, solver)
            print(f"{name:18s} {label:22s} {solver:8s} {acc:>30s} {res.u[0]:>11.6f} {gap:>12s} {us:>8.2f}")
    m1, m2, F = 1.0, 3.0, 2.0
    print(
        f"\nExpected (m1={m1}, m2={m2}, F={F}): rod → both accelerate at F/(m1+m2) = {F / (m1 + m2):.5f}; "
        f"servo → F/m2 = {F / m2:.5f} with servo force m1·F/m2 = {m1 * F / m2:.5f}."
    )
    print("µs/step: one compiled casadi call per step (Function.buffer), minimum over repeats.")
    print()
    _demo_scenes()
    return 0


#: Steps of compiled RK4 per scene in the demo (stiff or fast scenes need more).
_DEMO_STEPS = {"stiff-chain": 20_000, "andrews": 6_000}


def _demo_scenes() -> None:
    """Every scene: compiled RK4 by QP and by the direct step, constraint residual, verification by (23)."""
    from .integral import verify
    from .simulate import simulate

    print(
        f"Every scene, compiled RK4 with the direct step and with the Gauss QP ({qp.DEFAULT}), then verified by (23):\n"
    )
    header = (
        f"{'scene':19s} {'realizations':26s} {'T':>6s} {'steps':>6s} {'QP vs direct':>12s} {'|Φ|,|g| max':>11s} "
        f"{'energy bal.':>11s} {'(23) gap':>9s} {'motion':>6s} {'run ms':>7s}"
    )
    print(header)
    print("-" * len(header))
    for name in scenes.names():
        scene = scenes.get(name)
        T = min(scene.t_end, 2.0)
        steps = _DEMO_STEPS.get(name, 2000)
        kwargs: dict[str, Any] = dict(lam0=scene.lam0, method="rk4-compiled", dt=T / steps, record=max(steps // 400, 1))
        start = time.perf_counter()
        direct = simulate(scene.model, scene.q0, scene.v0, T, solver="direct", **kwargs)
        run_ms = (time.perf_counter() - start) * 1e3
        gauss = simulate(scene.model, scene.q0, scene.v0, T, solver="qp", **kwargs)
        scale = max(1.0, float(np.abs(np.hstack([direct.q, direct.v])).max()))
        diff = float(np.abs(np.hstack([gauss.q - direct.q, gauss.v - direct.v])).max()) / scale
        check = verify(scene.model, direct)
        balance = np.abs(direct.energy_balance())
        energy = f"{np.nanmax(balance):.1e}" if np.isfinite(balance).any() else "—"
        labels = ", ".join(dict.fromkeys(c.realization.label for c in scene.model.constraints))
        print(
            f"{name:19s} {labels:26s} {T:6.3g} {direct.steps:6d} {diff:12.1e} {direct.max_residual():11.1e} "
            f"{energy:>11s} {check.relative_gap:9.1e} {'yes' if check.is_motion else 'NO':>6s} {run_ms:7.1f}"
        )
    print(
        "\nQP vs direct: largest state difference (relative) along the whole run; (23) gap: relative gap of the\n"
        "integral principle for the direct run's path — zero up to discretization iff the path is a motion."
    )


def report(args: argparse.Namespace) -> int:
    """Work-precision study (or, with --stability, the stability study): table, CSV/JSON, plots."""
    from pathlib import Path

    from . import report as study

    out = Path(args.out)
    if args.stability:
        from . import stability

        cases = stability.run(quick=not args.full)
        print(stability.table(cases))
        out.mkdir(parents=True, exist_ok=True)
        (out / "stability.json").write_text(json.dumps(stability.to_records(cases), indent=1, default=str))
        print(f"\nwritten: {out / 'stability.json'}")
        return 0 if all(c.verdict for c in cases) else 1
    start = time.perf_counter()
    rows = study.work_precision(
        args.scenes or None,
        quick=not args.full,
        repeats=args.repeats,
        progress=(lambda m: print(f"  … {m}", file=sys.stderr)) if args.verbose else None,
    )
    print(study.table(rows))
    print("\nFastest run reaching a final-state error ≤ 1e-10, per scene:")
    for scene, row in study.best_per_scene(rows).items():
        shown = (
            "none"
            if row is None
            else f"{row.method} · {row.solver} · {row.setting}: {row.final_error:.1e} in {row.wall_time:.4f} s"
        )
        print(f"  {scene:20s} {shown}")
    files = study.write(rows, out)
    try:
        from . import plot

        files += plot.save_work_precision(rows, out)
    except GaussppError as exc:  # matplotlib missing: the table and data are still written
        print(f"(no plots: {exc})")
    print(f"\n{len(rows)} runs in {time.perf_counter() - start:.1f} s; written: {', '.join(str(f) for f in files)}")
    return 0


def list_scenes(args: argparse.Namespace) -> int:
    """Print every scene with a one-line description."""
    for name, line in scenes.describe().items():
        print(f"{name:20s} {line}")
    return 0


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="gausspp", description=__doc__.splitlines()[0])
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("demo", help="the main job: scenes solved by QP and direct, a table").set_defaults(func=demo)
    sub.add_parser("scenes", help="list the scenes").set_defaults(func=list_scenes)
    rep = sub.add_parser("report", help="error against run time for every scene, method and solver")
    rep.add_argument("--stability", action="store_true", help="run the stability study instead")
    rep.add_argument("--full", action="store_true", help="finer sweeps (and full-size stability cases)")
    rep.add_argument("--scenes", nargs="*", help="only these scenes")
    rep.add_argument("--repeats", type=int, default=2, help="timing repeats (the minimum is kept)")
    rep.add_argument("--out", default="report", help="directory for CSV/JSON and plots (default: report/)")
    rep.add_argument("--verbose", action="store_true", help="progress on stderr")
    rep.set_defaults(func=report)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gausspp`` command."""
    args = _parser().parse_args(argv)
    try:
        return int(args.func(args))
    except GaussppError as exc:
        if args.debug:
            raise
        print(f"gausspp: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
