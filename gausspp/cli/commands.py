"""The subcommands: each checks what argparse cannot, calls a study, prints its text; the exit code.

A :class:`~gausspp.cli.console.UsageError` is a command line that cannot be meant (exit 2); a
:class:`~gausspp.GaussppError` a value the library rejects or a run that failed (exit 1).
"""

from __future__ import annotations

import argparse
import inspect
import io
import json
import re
import sys
import time
from collections import Counter
from collections.abc import Callable, Iterable
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import redirect_stdout
from itertools import islice
from pathlib import Path
from typing import Any

import numpy as np

from .. import plot, scenes
from ..errors import GaussppError, UnknownNameError
from ..scenes.scene import kinds as parameter_kinds
from ..simulation import lanes, methods
from ..simulation.trajectory import Trajectory
from ..step import qp
from ..studies import demo as demo_study
from ..studies import demo_run, output, runs, stability, sweeps, tables
from ..studies import report as study
from ..verification.verify import verify as check
from .console import EXIT_OK, Progress, RowProgress, UsageError, warnings_as_lines
from .params import build, parse_params


def _print(lines: Iterable[str]) -> None:
    for line in lines:
        print(line)


def _out_folder(out: Path, command: str) -> Path:
    """``--out`` of a command that writes a folder, refused before the work if a file stands at it or above it."""
    blocking = next((p for p in (out, *out.parents) if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise UsageError(f"--out for {command} is a folder; {str(blocking)!r} is a file: choose another path")
    return out


# -- demo ---------------------------------------------------------------------------------------------
def demo(args: argparse.Namespace) -> int:
    """Two masses, rod vs servo, and the rigid-body servo: QP vs direct, table and timings; every scene;
    the general Gauss QP's scenes; the teaching figures. The rows run on worker processes; each table
    prints whole as soon as its rows are ready, with a line per finished row (and a bar) on stderr between tables."""
    which = demo_study.backends()
    plan = demo_run.plan(which, _out_folder(Path(args.out), "demo"))
    counts = Counter(task.table for task in plan)
    progress = RowProgress(len(plan), "gausspp demo", enabled=not getattr(args, "quiet", False))
    try:
        results = demo_run.run(plan, demo_run.workers(), lambda task, s: progress.done(f"{task.table} {task.name}", s))
        steps = (row for pair in islice(results, counts["step"]) for row in pair)
        for lines in (
            tables.step_lines(steps, qp.DEFAULT),
            tables.scene_lines(islice(results, counts["scene"]), qp.DEFAULT),
            tables.general_lines(which, demo_run.general_rows(which, islice(results, counts["general"]))),
        ):
            for line in list(lines):  # the whole table first: progress lines come between tables, never inside
                progress.emit(line)
        try:
            written = list(islice(results, counts["figures"]))
        except GaussppError as exc:  # matplotlib is an optional extra
            progress.emit(f"\n(no figures: {exc})")
            return EXIT_OK
    finally:
        progress.close()
    print(f"\nfigures written: {', '.join(str(p) for p in written)}")
    return EXIT_OK


# -- report -------------------------------------------------------------------------------------------
def _save_plots(rows: list[study.Row], out: Path) -> list[Path]:
    known = set(scenes.names())
    titles = {name: tables.scalar_parameters(scenes.get(name).params) for name in {r.scene for r in rows} & known}
    try:
        return plot.save_work_precision(rows, out, titles)
    except GaussppError as exc:  # matplotlib missing: the table and data are still written
        print(f"(no plots: {exc})")
        return []


def _stability(args: argparse.Namespace, out: Path) -> int:
    cases = stability.run(quick=not args.full)
    print(stability.table(cases))
    out.mkdir(parents=True, exist_ok=True)
    (out / "stability.json").write_text(json.dumps(stability.to_records(cases), indent=1, default=str))
    print(f"\nwritten: {out / 'stability.json'}")
    return 0 if all(c.verdict for c in cases) else 1


def report(args: argparse.Namespace) -> int:
    """Work-precision study (or, with --stability, the stability study): table, CSV/JSON, plots."""
    out = _out_folder(Path(args.out), "report")  # before the study, not after it
    if args.stability:
        return _stability(args, out)
    start = time.perf_counter()
    rows = study.work_precision(
        args.scenes or None,
        quick=not args.full,
        repeats=args.repeats,
        progress=(lambda m: print(f"  … {m}", file=sys.stderr)) if args.verbose else None,
    )
    _print(study.summary_lines(rows))
    files = study.write(rows, out)
    files += _save_plots(rows, out)
    print(f"\n{len(rows)} runs in {time.perf_counter() - start:.1f} s; written: {', '.join(str(f) for f in files)}")
    return 0


# -- run, verify ----------------------------------------------------------------------------------------
def _step_options(args: argparse.Namespace, scene: scenes.Scene, meth: methods.Method) -> dict[str, Any]:
    """``solver``, ``backend`` and ``stabilize`` of :func:`gausspp.simulate` as the command line asks."""
    solver, backend = getattr(args, "solver", None), getattr(args, "backend", None)
    if solver is None:  # the scene's own (a redundant robot: qp), if the lane takes it, else the lane's default
        wanted = scene.params.get("solver")
        solver = wanted if wanted is not None and lanes.accepts(meth, wanted) else lanes.default_solver(meth)
    elif not lanes.accepts(meth, solver):
        lane = lanes.lane_of(meth, lanes.KINDS[lanes.SMOOTH])
        raise UsageError(f"--method {meth.name} needs --solver {' or '.join(lane.solvers)} ({lane.solver_reason})")
    stabilize = getattr(args, "stabilize", None)
    if stabilize is None:  # the scene's own drift control (a bounded servo's feedback), else none
        stabilize = scene.params.get("stabilize", "none")
    if backend is not None:
        if solver == "direct":
            raise UsageError("--backend applies to --solver qp only")
        try:  # unknown or unavailable backends fail here, naming the valid ones (probing them prints banners)
            with redirect_stdout(io.StringIO()):
                qp.get(backend)
        except UnknownNameError as exc:
            raise UsageError(f"--backend {backend}: {exc}") from None
    return dict(solver=solver, backend=backend, stabilize=None if stabilize == "none" else stabilize)


def _simulate(
    args: argparse.Namespace, scene: scenes.Scene, label: str, *, every_step: bool = False
) -> tuple[Trajectory, float, float | None]:
    """Simulate ``scene`` as the command line says (:func:`gausspp.studies.runs.simulate_scene`), with
    progress and warnings on stderr: the trajectory, the wall time in s, the ``dt`` used."""
    meth = methods.get(args.method)
    t_end = scene.t_end if args.t_end is None else args.t_end
    options = _step_options(args, scene, meth)
    with Progress(label, enabled=not args.quiet), warnings_as_lines():
        return runs.simulate_scene(
            scene,
            meth,
            t_end,
            dt=args.dt,
            samples=args.samples,
            every_step=every_step,
            rtol=args.rtol,
            atol=args.atol,
            constraint_tol=args.constraint_tol,
            **options,
        )


def run(args: argparse.Namespace) -> int:
    """Simulate one scene, print a summary, optionally write the trajectory (a directory: NPZ, CSV, PNG; or one
    ``.npz``/``.nc`` file, :func:`gausspp.studies.output.write_trajectory`)."""
    params = parse_params(args.scene, args.param)
    scene = build(args.scene, params)
    animation = args.animate
    if animation is not None:
        plot.animation.drawing_of(scene)  # refused before the run, not after
        output.check_file_target(Path(animation), "--animate")
    if args.out is not None:
        output.check_out(Path(args.out), scene.name)  # a path that cannot be written is refused before the run
    traj, wall, dt = _simulate(args, scene, f"simulating {args.scene}")
    print(tables.label(scene.name, params))
    _print(runs.summary_lines(scene, traj, wall, dt, args.rtol))
    if args.out is not None:
        files = output.write_trajectory(traj, scene, params, Path(args.out))
        print(f"  {'written':15s} {', '.join(str(f) for f in files)}")
    if animation is not None:
        plot.animate(scene, traj, out=animation)
        print(f"  {'animation':15s} {animation}")
    if not traj.success:
        raise GaussppError(f"the run {traj.status}: {tables.one_line(traj.message)}")
    return EXIT_OK


def verify(args: argparse.Namespace) -> int:
    """Simulate a scene, then decide by (23) whether the path is a motion of its model (or of another)."""
    params = parse_params(args.scene, args.param)
    check_params = parse_params(args.scene, args.check_param, "--check-param")
    scene = build(args.scene, params)
    model = build(args.scene, {**params, **check_params}).model if check_params else scene.model
    traj, wall, dt = _simulate(args, scene, f"simulating {args.scene}", every_step=True)
    t_end = scene.t_end if args.t_end is None else args.t_end
    traj = runs.thin(traj, 0.05 * t_end / args.samples)
    print(f"path:     {tables.label(scene.name, params)} — {tables.realizations(scene.model)}")
    reached = f" to t = {traj.t[-1]:.6g}" if len(traj) else ""
    print(f"          {traj.method} ({runs.setting(traj, dt, args.rtol)}), {len(traj)} samples{reached}, {wall:.3g} s")
    if traj.status == "failed":
        raise GaussppError(f"the simulation failed, nothing to verify: {tables.one_line(traj.message)}")
    target = tables.label(scene.name, {**params, **check_params}) if check_params else "the same model"
    print(f"model:    {target} — {tables.realizations(model)}")
    with Progress("verifying by (23)", enabled=not args.quiet), warnings_as_lines():
        start = time.perf_counter()
        result = check(model, traj)
        wall = time.perf_counter() - start
    _print(runs.verification_lines(result, wall))
    verdict, reason = runs.verdict(result)
    print(f"verdict:  {verdict} {reason}")
    if args.expect is not None and (args.expect == "motion") != result.is_motion:
        raise GaussppError(f"expected {args.expect.replace('-', ' ')}, but the verdict is: {verdict}")
    return EXIT_OK


# -- scenes ---------------------------------------------------------------------------------------------
_ROLE = re.compile(r":\w+:`~?([^`]+)`")
_LITERAL = re.compile(r"``([^`]+)``")


def plain(text: str) -> str:
    """Docstring markup as a terminal shows it: ``x`` → x, :func:`gausspp.simulate` → gausspp.simulate."""
    return _LITERAL.sub(r"\1", _ROLE.sub(r"\1", text))


def list_scenes(args: argparse.Namespace) -> int:
    """Every scene with a one-line description, or one scene's description and, for each parameter, its type,
    default and unit on one line, then its meaning and allowed values below (the builder's "Parameters")."""
    import textwrap

    from ..scenes import parameter_docs

    if args.name is None:
        for name, line in scenes.describe().items():
            print(f"{name:20s} {plain(line)}")
        return EXIT_OK
    builder = scenes._builder(args.name)
    doc = plain(parameter_docs.without_parameters(inspect.getdoc(builder)))
    print(f"{args.name}: {doc}\n\nparameters (gausspp run {args.name} --param KEY=VALUE):")
    params, docs = scenes.parameters(args.name), parameter_docs.describe(args.name)
    kinds = {key: plain(d.kind) or " | ".join(sorted(parameter_kinds(params[key]))) or "any" for key, d in docs.items()}
    defaults = {key: f"default {d.default!r}" for key, d in docs.items()}
    widths = [max(map(len, column), default=0) for column in (docs, kinds.values(), defaults.values())]
    for key, d in docs.items():
        unit = f"({d.unit})" if d.unit else "(unit not documented)"
        print(f"  {key:{widths[0]}s}  {kinds[key]:{widths[1]}s}  {defaults[key]:{widths[2]}s}  {unit}".rstrip())
        body = [plain(d.meaning) or "(not documented)", f"allowed: {plain(d.allowed) or 'not documented'}"]
        for text in body:
            print(
                textwrap.fill(
                    text,
                    100,
                    initial_indent=" " * 6,
                    subsequent_indent=" " * 8,
                    break_on_hyphens=False,
                    break_long_words=False,
                )
            )
    return EXIT_OK


# -- sweep ----------------------------------------------------------------------------------------------
_SWEEP_ONLY = {
    "realizability": ("resolution",),
    "work-precision": ("scenes", "methods", "solvers", "full", "repeats"),
}


def sweep(args: argparse.Namespace) -> int:
    """A parameter sweep on local worker processes, appended to --out as it runs (resumable)."""
    for name, options in _SWEEP_ONLY.items():
        for option in options:
            if name != args.study and getattr(args, option) is not None:
                raise UsageError(f"--{option} applies to `gausspp sweep {name}` only")
    pool: Executor | None = ProcessPoolExecutor(args.workers) if args.workers > 1 else None
    run_study: Callable[[argparse.Namespace, Any], int] = (
        _sweep_realizability if args.study == "realizability" else _sweep_work_precision
    )
    try:
        return run_study(args, pool or "serial")
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _workers_text(args: argparse.Namespace) -> str:
    return f"{args.workers} worker{'s' if args.workers > 1 else ''}"


def _sweep_realizability(args: argparse.Namespace, executor: Any) -> int:
    step = 2.0 if args.resolution is None else args.resolution
    if not (np.isfinite(step) and 0 < step <= 30):
        raise UsageError(f"--resolution is a grid step in degrees, 0 < R ≤ 30; got {step}")
    lon = np.linspace(-180.0, 180.0, int(round(360 / step)) + 1)
    lat = np.linspace(-90.0, 90.0, int(round(180 / step)) + 1)
    params = sweeps.grid(lat=[float(x) for x in lat], lon=[float(x) for x in lon])
    res = sweeps.sweep(sweeps.realizability_task, params, executor=executor, out=args.out, progress=not args.quiet)
    margin = res.column("margin")
    k = int(np.nanargmin(margin)) if np.isfinite(margin).any() else 0
    print(
        f"realizability of a servo torque along n over the sphere, I = diag(1, 2, 3), l = (1, 1, 1)/√3, "
        f"{step:g}° grid: {len(res)} directions"
    )
    print(
        f"computed {res.computed} in {res.wall_time:.2f} s ({res.tasks_per_second:.0f} tasks/s, "
        f"{_workers_text(args)}); failed: {len(res.errors)}"
    )
    print(
        f"smallest margin {margin[k]:.3e} at lon {params[k]['lon']:g}°, lat {params[k]['lat']:g}°; "
        f"largest {np.nanmax(margin):.3f}"
    )
    if args.out:
        print(f"written: {args.out} (JSON lines; run again to resume)")
    return 0 if res.ok else 1


def _work_precision_out(args: argparse.Namespace) -> Path:
    if args.solvers:
        known = ["direct", *qp.names()]
        for solver in args.solvers:
            if solver not in known:
                raise UsageError(f"--solvers: {solver!r} is unknown; use {', '.join(known)}")
    return _out_folder(Path(args.out or "report"), "work-precision")


def _sweep_work_precision(args: argparse.Namespace, executor: Any) -> int:
    out = _work_precision_out(args)
    log = out / "work_precision.jsonl"
    rows, res = sweeps.work_precision(
        args.scenes or None,
        args.methods or None,
        args.solvers or None,
        quick=not args.full,
        repeats=2 if args.repeats is None else args.repeats,
        executor=executor,
        out=log,
        progress=not args.quiet,
    )
    _print(study.summary_lines(rows))
    files = [log, *study.write(rows, out)]
    files += _save_plots(rows, out)
    print(
        f"\n{len(rows)} runs; computed {res.computed} of {len(res)} tasks in {res.wall_time:.1f} s "
        f"({_workers_text(args)}{'; wall times measured side by side in the workers' if args.workers > 1 else ''}); "
        f"failed tasks: {len(res.errors)}"
    )
    print(f"written: {', '.join(str(f) for f in files)} (run again with the same --out to resume)")
    return 0 if res.ok else 1
