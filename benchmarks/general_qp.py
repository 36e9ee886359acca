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

MuJoCo peers (optional: the peers extra, ``pip install 'gausspp[peers]'``; one line says when mujoco is
missing): the same four-bar (2 s), the block dropped on the floor (3 s) and a ladder of ``N`` parallelogram
cells side by side (1 s, ``N`` = 4 … 64), as MJCF with hinges, slides and ``connect`` equalities
(``benchmarks/_mujoco_peers.py``), RK4 at ``dt = 1e-3``: the whole run's wall, µs per step, the constraint
violation at the end; the four-bar's crank angle beside gausspp's minimal model's. ``--peers-only`` prints
only these rows.

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


def mujoco_section(budget: float, repeats: int) -> None:
    """The MuJoCo peer rows (``benchmarks/_mujoco_peers.py``), or one line saying the peers extra is missing."""
    try:
        import mujoco
    except ImportError:
        print("MuJoCo peer rows skipped: mujoco is not installed (the peers extra: pip install 'gausspp[peers]')")
        return
    import _mujoco_peers as mjp

    print(
        f"MuJoCo {mujoco.__version__} peers: RK4, dt = {mjp.DT:g}, whole runs in MuJoCo's loop (mj_step nstep); "
        f"connect equalities at the stiffest softness ({mjp.stiffest()})"
    )
    header = f"{'case':<44} {'route':<38} {'wall ms':>9} {'µs/step':>9} {'violation':>9}  note"
    print(header + "\n" + "-" * (len(header) + 30))

    def line(case: str, route: str, wall_ms: float, step_us: float, violation: float, note: str = "") -> None:
        times = f"{_num(wall_ms, '.2f')} {_num(step_us, '.2f')} {_num(violation, '.1e')}"
        print(f"{case:<44} {route:<38} {times}  {note}".rstrip())

    # -- four-bar, 2 s: MuJoCo's hinge chain closed by one connect, beside gausspp's minimal model ------
    scene = four_bar.build(redundant=False)
    p = scene.params
    geometry = {k: p[k] for k in ("l0", "l1", "l2", "l3", "rho", "g", "theta0", "omega0")}
    fb = mjp.four_bar(scene.t_end, budget=budget, repeats=repeats, **geometry)
    steps = round(scene.t_end / mjp.DT)

    def simulate() -> Any:
        return gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, dt=mjp.DT, method="rk4", lane="compiled")

    ref = simulate().q[-1]
    ref_us = best_us(simulate, budget, repeats)
    phi = np.cumsum(ref)  # absolute angles
    closure = p["l1"] * np.exp(1j * phi[0]) + p["l2"] * np.exp(1j * phi[1]) + p["l3"] * np.exp(1j * phi[2]) - p["l0"]
    case = f"four-bar-redundant, {scene.t_end:g} s (θ1 = π/2, ω0 = {p['omega0']:g})"
    note = f"θ1(T) = {fb['theta1']:.6f} rad, − gausspp: {fb['theta1'] - ref[0]:+.1e}; "
    note += f"energy drift {fb['energy_drift']:.0e}"
    line(case, "MuJoCo hinge chain + 1 connect", fb["wall_ms"], fb["step_us"], fb["violation"], note)
    note = f"θ1(T) = {ref[0]:.6f} rad"
    line("", "gausspp minimal: simulate rk4 compiled", ref_us / 1e3, ref_us / steps, abs(closure), note)

    # -- block dropped on the floor, 3 s ------------------------------------------------------------------
    bd = mjp.box_drop(budget=budget, repeats=repeats)
    case = "block-on-floor, 3 s (drop 1 m, e = 0.5)"
    note = (
        f"restitution {bd['restitution']:.3f} (contact ζ {bd['damping_ratio']:.3f}), first impact "
        f"{bd['first_impact']:.3f} s (exact {math.sqrt(2 / 9.81):.3f}); last 0.5 s: corner within "
        f"{bd['rest_band']:.0e} m of the floor, |q̇| ≤ {bd['rest_speed']:.0e}, "
        f"{bd['airborne']:.0%} of steps without contact"
    )
    line(case, "MuJoCo slide x, z + hinge y on a plane", bd["wall_ms"], bd["step_us"], bd["violation"], note)
    line("", "MuJoCo: one mj_step resting", math.nan, bd["rest_step_us"], math.nan)

    # -- ladder of N parallelogram cells, 1 s ---------------------------------------------------------------
    sizes, per_step = (4, 8, 16, 32, 64), []
    for n in sizes:
        ld = mjp.parallelogram_ladder(n, budget=budget, repeats=repeats)
        per_step.append(ld["step_us"])
        case = "parallelogram ladder, 1 s (tips 1 m/s)" if n == sizes[0] else ""
        route = f"MuJoCo N = {n}: {ld['nv']} hinges, {n} connects"
        note = (
            f"crank turned {ld['angle']:.4f} rad (− one-DOF model: {ld['angle_error']:+.0e}), spread {ld['spread']:.0e}"
        )
        line(case, route, ld["wall_ms"], ld["step_us"], ld["violation"], note)
    fits = [mjp.growth_exponent(list(sizes[k:]), per_step[k:]) for k in (0, 2)]
    print(f"\nMuJoCo ladder: µs/step ∝ N^{fits[0]:.2f} (least squares over N = {sizes[0]} … {sizes[-1]}; ", end="")
    print(f"N^{fits[1]:.2f} over N = {sizes[2]} … {sizes[-1]})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="~0.02 s per repeat instead of ~0.1 s")
    parser.add_argument("--repeats", type=int, default=3, help="timing repeats; the minimum is reported")
    parser.add_argument("--peers-only", action="store_true", help="only the MuJoCo peer rows")
    args = parser.parse_args()
    budget = 0.02 if args.quick else 0.1
    start = perf_counter()
    print(
        f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs; python "
        f"{platform.python_version()}, casadi {ca.__version__}, qpsolvers {qpsolvers.__version__}; "
        f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}"
    )
    print(f"timing: min of {args.repeats} repeats of ~{budget:g} s each\n")
    if args.peers_only:
        mujoco_section(budget, args.repeats)
        print(f"(total {perf_counter() - start:.1f} s)")
        return
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
    print(f"\nlargest daqp–OSQP disagreement on these steps: {worst:.1e}\n")
    mujoco_section(budget, args.repeats)
    print(f"(total {perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.RealizabilityWarning)
        main()
