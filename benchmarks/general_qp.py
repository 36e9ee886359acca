"""The general Gauss QP per step (daqp, OSQP, casadi:qrqp) on the issue-7 scenes: ``python benchmarks/general_qp.py``.

Cases (one state each):

* ``saturated-crane`` with a bound the step does not reach (F_max = 20) and one it does (F_max = 12),
  beside the plain ``crane`` (the same servo unbounded: compiled direct and compiled QP steps);
* ``two-actuator-servo`` unbounded (two rotors, one row: the compiled QP can solve it, the direct
  formula cannot), with rotor 1 bounded below its lever-rule share (reallocation, tracking error 0)
  and with both rotors too weak (saturated, tracked);
* ``four-bar-redundant`` (three loop rows of rank 2), beside the minimal model's compiled steps.

Columns: ``step µs`` — the checked ``Model.general_step`` / ``Model.step`` (model data from casadi,
the QP stages, result packaging); ``QP µs`` — :func:`gausspp.step.general.solve_general` alone on the
same :class:`~gausspp.step.general.GaussProblem`; ``vs daqp`` — the largest relative difference in the
acceleration and (where the unknowns are the same) the reaction from the general QP with daqp.
Each time is the minimum over repeats of the mean per-call time (noise only adds time).

The general QP calls ``scipy.linalg.solve_triangular`` with several right-hand sides; with a
multi-threaded OpenBLAS on a busy machine a single such call has been measured at up to 3 ms
(15 µs single-threaded). Run with ``OPENBLAS_NUM_THREADS=1`` to see the code's own cost; the header
prints the setting in force.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import warnings
from dataclasses import dataclass
from time import perf_counter
from typing import Any

import casadi as ca
import numpy as np
import qpsolvers
from _timing import best_us

import gausspp as gp
import gausspp.step.general.general_step as _general_step
from gausspp.scenes import crane, four_bar, saturated_crane
from gausspp.scenes import two_actuator_servo as tas
from gausspp.step.general import GaussProblem, solve_general
from gausspp.step.results import StepResult

#: Backends of the general QP compared, by registry name ("daqp", "osqp": qpsolvers' solvers; casadi:qrqp: the
#: compiled step's default, through casadi's conic with bounds and inequalities).
GENERAL = ("daqp", "osqp", "casadi:qrqp")


@dataclass
class Row:
    case: str
    route: str
    step: float = math.nan  # µs, model.step / model.general_step
    qp: float = math.nan  # µs, solve_general alone
    disagreement: float = math.nan
    note: str = ""


def captured_problem(model: gp.Model, t: float, q: np.ndarray, v: np.ndarray) -> GaussProblem:
    """The GaussProblem ``model.general_step`` hands to the QP at this state."""
    seen: list[GaussProblem] = []
    original = _general_step.solve_general

    def capture(problem: GaussProblem, backend: Any = None, *args: Any, **kwargs: Any) -> Any:
        seen.append(problem)
        return original(problem, backend, *args, **kwargs)

    _general_step.solve_general = capture  # type: ignore[assignment]
    try:
        model.general_step(t, q, v)
    finally:
        _general_step.solve_general = original
    return seen[-1]


def relative(x: np.ndarray, y: np.ndarray) -> float:
    scale = max(float(np.max(np.abs(x))), float(np.max(np.abs(y))), 1e-300)
    return float(np.max(np.abs(x - y))) / scale


def compare(result: StepResult, reference: StepResult, same_unknowns: bool) -> float:
    if same_unknowns and result.u.shape == reference.u.shape:
        return result.disagreement(reference)
    return relative(result.a, reference.a)


def general_rows(
    case: str, model: gp.Model, state: tuple[float, np.ndarray, np.ndarray], budget: float, repeats: int
) -> tuple[list[Row], StepResult]:
    t, q, v = state
    problem = captured_problem(model, t, q, v)
    rows, reference = [], model.general_step(t, q, v, backend="daqp")[0]
    for be in GENERAL:
        row = Row(case, f"general QP, {be}")
        try:
            result, sol = model.general_step(t, q, v, backend=be)
            row.disagreement = result.disagreement(reference)
            row.step = best_us(lambda: model.general_step(t, q, v, backend=be), budget, repeats)
            row.qp = best_us(lambda: solve_general(problem, be), budget, repeats)
            flags = []
            if sol.tracking_error > 0:
                flags.append(f"tracking error {sol.tracking_error:.3g}")
            if sol.at_bound.any():
                flags.append(f"at bound {sol.at_bound.astype(int).tolist()}")
            if sol.redundant_rows:
                flags.append(f"{sol.redundant_rows} redundant row(s)")
            row.note = ", ".join(flags)
        except Exception as exc:  # kept in the table, never dropped
            row.note = f"{type(exc).__name__}: {exc}"
        rows.append(row)
    return rows, reference


def compiled_rows(
    case: str,
    model: gp.Model,
    state: tuple[float, np.ndarray, np.ndarray],
    reference: StepResult,
    budget: float,
    repeats: int,
    label: str,
    same_unknowns: bool = True,
) -> list[Row]:
    t, q, v = state
    rows = []
    for solver, backend in (("direct", None), ("qp", None), ("qp", "qpsolvers:daqp")):
        name = "direct" if solver == "direct" else (backend or gp.qp.DEFAULT)
        row = Row(case, f"{label}: {name}")
        try:
            result = model.step(t, q, v, solver=solver, backend=backend)
            row.disagreement = compare(result, reference, same_unknowns)
            row.step = best_us(lambda: model.step(t, q, v, solver=solver, backend=backend), budget, repeats)
            if result.solver.startswith("gauss-qp"):
                row.note = f"fell back to {result.solver}"
        except Exception as exc:
            row.note = f"{type(exc).__name__}: {str(exc)[:60]}…"
        rows.append(row)
    return rows


def _num(x: float, fmt: str, width: int = 9) -> str:
    return format(x, fmt).rjust(width) if np.isfinite(x) else "—".rjust(width)


def print_table(rows: list[Row]) -> None:
    header = f"{'case':<44} {'route':<38} {'step µs':>9} {'QP µs':>9} {'vs daqp':>9}  note"
    print(header + "\n" + "-" * (len(header) + 30))
    last = None
    for r in rows:
        case = r.case if r.case != last else ""
        last = r.case
        times = f"{_num(r.step, '.1f')} {_num(r.qp, '.1f')} {_num(r.disagreement, '.1e')}"
        print(f"{case:<44} {r.route:<38} {times}  {r.note}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="~0.02 s per repeat instead of ~0.1 s")
    parser.add_argument("--repeats", type=int, default=3, help="timing repeats; the minimum is reported")
    args = parser.parse_args()
    budget = 0.02 if args.quick else 0.1
    start = perf_counter()
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; python "
        f"{platform.python_version()}, casadi {ca.__version__}, qpsolvers {qpsolvers.__version__}; "
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}"
    )
    print(f"timing: min of {args.repeats} repeats of ~{budget:g} s each\n")
    rows: list[Row] = []

    # -- crane: a state where the unbounded servo needs 12.51 N ------------------------------------
    plain = crane.build()
    state = (1.0, plain.q0 + np.array([0.1, 0.05]), np.array([0.3, -0.2]))
    for F_max, what in ((20.0, "not reached"), (12.0, "saturated")):
        case = f"saturated-crane F_max={F_max:g} ({what})"
        general, reference = general_rows(case, saturated_crane.build(F_max=F_max).model, state, budget, args.repeats)
        rows += general
        if F_max == 20.0:
            rows += compiled_rows(case, plain.model, state, reference, budget, args.repeats, "crane (unbounded)")

    # -- two rotors, one altitude row ----------------------------------------------------------------
    state = (0.6, np.array([0.1, 0.2, 0.3]), np.array([0.2, 0.4, -0.5]))
    for f_max, what in ((None, "unbounded"), ((6.0, np.inf), "rotor 1 ≤ 6: reallocated"), ((4.0, 5.0), "saturated")):
        case = f"two-actuator-servo {what}"
        scene = tas.build(f_max=f_max)
        general, reference = general_rows(case, scene.model, state, budget, args.repeats)
        rows += general
        if f_max is None:
            rows += compiled_rows(case, scene.model, state, reference, budget, args.repeats, "compiled")

    # -- four-bar: three loop rows of rank 2 ---------------------------------------------------------
    q, v = four_bar.assemble(1.0, 6.0, 1.0, 0.3, 1.0, 0.8)
    state = (0.0, q, v)
    case = "four-bar-redundant (oblique)"
    redundant, minimal = four_bar.build(), four_bar.build(redundant=False)
    general, reference = general_rows(case, redundant.model, state, budget, args.repeats)
    rows += general
    rows += compiled_rows(case, redundant.model, state, reference, budget, args.repeats, "redundant model.step")
    rows += compiled_rows(case, minimal.model, state, reference, budget, args.repeats, "minimal", same_unknowns=False)

    print_table(rows)
    worst = max((r.disagreement for r in rows if r.route.endswith("osqp") and np.isfinite(r.disagreement)), default=0)
    print(f"\nlargest daqp–OSQP disagreement on these steps: {worst:.1e}")
    print(f"(total {perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.RealizabilityWarning)
        main()
