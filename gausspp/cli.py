"""Command line: ``gausspp demo`` (the main job), ``run``, ``verify``, ``report`` and ``scenes``.

Exit codes: 0 success; 1 a gausspp error (a value the library rejects, a run that failed midway,
a file that cannot be written); 2 a malformed command line (unknown command, option, scene,
method, solver or scene parameter, a parameter value of the wrong type); 130 interrupted.
Errors print as one line on stderr (the traceback only with ``--debug``).
"""

from __future__ import annotations

import argparse
import ast
import inspect
import io
import json
import os
import sys
import threading
import time
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, redirect_stdout
from dataclasses import replace
from pathlib import Path
from typing import IO, Any, NoReturn

import numpy as np

from . import scenes
from .errors import GaussppError, LongRunWarning, UnknownNameError
from .model.model import Model
from .scenes._scene import kinds as parameter_kinds
from .simulation import methods
from .simulation.trajectory import Trajectory
from .step import qp
from .verification.crosscheck import crosscheck

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


class UsageError(Exception):
    """A command line that parses but cannot be meant (unknown parameter, value of the wrong type): exit 2."""


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


# -- progress, warnings --------------------------------------------------------------------------
class _Progress:
    """Elapsed time on stderr while a long call runs: a spinner line on a terminal, sparse lines otherwise.

    Nothing is shown for calls shorter than ``delay`` seconds. Calls into compiled code that hold
    the GIL pause the spinner; the elapsed time is right again when they return.
    """

    _FRAMES = "|/-\\"
    _LOG_AT = (2.0, 10.0, 30.0, 60.0)  # non-terminal: one line at these elapsed times, then every minute

    def __init__(self, label: str, enabled: bool = True, delay: float = 1.0) -> None:
        self.label, self.enabled, self.delay = label, enabled, delay
        self.shown = False
        self._done = threading.Event()
        self._thread: threading.Thread | None = None
        self._stream: IO[str] = sys.stderr

    def __enter__(self) -> _Progress:
        if self.enabled:
            self._stream = sys.stderr
            self._start = time.perf_counter()
            self._thread = threading.Thread(target=self._loop, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._done.set()
        if self._thread is not None:
            self._thread.join()
        if self.shown:
            if self._tty():
                self._stream.write("\r\033[K")
            else:
                self._stream.write(f"gausspp: {self.label}: done in {time.perf_counter() - self._start:.1f} s\n")
            self._stream.flush()

    def _tty(self) -> bool:
        try:
            return bool(self._stream.isatty())
        except (AttributeError, ValueError):
            return False

    def _loop(self) -> None:
        if self._done.wait(self.delay):
            return
        tty, frame, marks = self._tty(), 0, list(self._LOG_AT)
        while not self._done.is_set():
            elapsed = time.perf_counter() - self._start
            if tty:
                self._stream.write(f"\r{self._FRAMES[frame % 4]} {self.label} … {elapsed:.1f} s")
                self._stream.flush()
                self.shown, frame = True, frame + 1
            elif elapsed >= marks[0]:
                self._stream.write(f"gausspp: {self.label} … {elapsed:.0f} s\n")
                self._stream.flush()
                self.shown = True
                marks = marks[1:] or [marks[0] + 60.0]
            self._done.wait(0.2)


@contextmanager
def _warnings_as_lines() -> Iterator[None]:
    """Show warnings raised inside as one line each on stderr (``gausspp: warning: ...``), once per message:
    a :class:`~gausspp.LongRunWarning` at once (it announces the wait), the others when the block ends."""
    caught: list[tuple[type[Warning], str]] = []
    seen: set[str] = set()

    def show(category: type[Warning], message: object) -> None:
        line = _one_line(message)
        if line not in seen:
            seen.add(line)
            print(f"gausspp: warning: {category.__name__}: {line}", file=sys.stderr, flush=True)

    def collect(message: Warning | str, category: type[Warning], *_: object, **__: object) -> None:
        if issubclass(category, LongRunWarning):
            show(category, message)
        else:
            caught.append((category, str(message)))

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = collect
        try:
            yield
        finally:
            for category, message in caught:
                show(category, message)


# -- scene parameters ------------------------------------------------------------------------------
def _scene_parameters(name: str) -> dict[str, inspect.Parameter]:
    """The keyword parameters of the scene's builder (:func:`gausspp.scenes.parameters`)."""
    return scenes.parameters(name)


def _parse_value(option: str, key: str, text: str, param: inspect.Parameter) -> Any:
    """``text`` as a Python literal (number, tuple, None, …), a plain string otherwise; checked against the type."""
    try:
        value: Any = ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        value = text
    kinds = parameter_kinds(param)
    if kinds == {"str"}:
        return value if isinstance(value, str) else text
    if kinds & {"float", "int"}:
        if value is None and "None" in kinds:
            return None
        if isinstance(value, str):
            try:
                value = float(value)  # inf, nan
            except ValueError:
                pass
        wanted = "an integer" if "float" not in kinds else "a number"
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise UsageError(
                f"{option} {key}={text}: {key} must be {wanted}"
                + (" or None" if "None" in kinds else "")
                + f", got {text!r}"
            )
        if "float" not in kinds:
            if not float(value).is_integer():
                raise UsageError(f"{option} {key}={text}: {key} must be an integer, got {text!r}")
            return int(value)
        return float(value)
    return value


def _parse_params(scene: str, items: Sequence[str] | None, option: str = "--param") -> dict[str, Any]:
    """``["k=v", ...]`` → keyword arguments of the scene's builder (names and value types checked)."""
    known = _scene_parameters(scene)
    params: dict[str, Any] = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"{option} {item!r}: expected KEY=VALUE, e.g. {option} t_end=2")
        if key not in known:
            raise UsageError(
                f"{option} {key}: scene {scene!r} has no parameter {key!r}; its parameters: {', '.join(known)}"
            )
        params[key] = _parse_value(option, key, text.strip(), known[key])
    return params


def _build(name: str, params: dict[str, Any]) -> scenes.Scene:
    try:
        return scenes.get(name, **params)
    except GaussppError:
        raise
    except (TypeError, ValueError) as exc:  # a value the builder could not use, not caught by the library
        raise GaussppError(f"scene {_label(name, params)}: {_one_line(exc)}") from exc


def _label(name: str, params: dict[str, Any]) -> str:
    return name + (" (" + ", ".join(f"{k}={v!r}" for k, v in params.items()) + ")" if params else "")


def _realizations(model: Model) -> str:
    parts = [f"{n}: {c.realization.label}" for n, c in zip(model.names, model.constraints, strict=True)]
    parts += [
        f"{n}: unilateral, e = {c.restitution:g}" for n, c in zip(model.contact_names, model.contacts, strict=True)
    ]
    return ", ".join(parts)


def _vector(x: np.ndarray) -> str:
    return np.array2string(np.asarray(x), precision=8, separator=", ", max_line_width=200, suppress_small=False)


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
        f"{'multiplier':>11s} {'QP vs direct':>12s} {'vs reference':>12s} {'µs/step':>8s}"
    )
    print(header)
    print("-" * len(header))
    for name, params in cases:
        scene = scenes.get(name, **params)
        model = scene.model
        lam = scene.lam0 if scene.lam0 is not None else np.zeros(0)
        # each solver's raw answer (no refinement), and the independent acceleration-space QP as the reference
        direct = model.step(0.0, scene.q0, scene.v0, solver="direct", refine=False)
        gauss = model.step(0.0, scene.q0, scene.v0, solver="qp", refine=False)
        check = crosscheck(model, 0.0, scene.q0, scene.v0, scene.lam0)
        label = params.get("realization") or (
            "Suslov (n = l)"
            if scene.params.get("suslov")
            else "servo n=(" + ", ".join(f"{x:.2f}" for x in scene.params["n"]) + ")"
        )
        for res, solver in ((direct, "direct"), (gauss, "qp")):
            acc = np.array2string(res.a, precision=5, suppress_small=True, separator=", ")
            gap = "" if solver == "direct" else f"{gauss.disagreement(direct):.1e}"
            versus = check.distances["direct" if solver == "direct" else "qp:default"]
            us = _time_per_step(model, 0.0, scene.q0, scene.v0, lam, solver)
            print(
                f"{name:18s} {label:22s} {solver:8s} {acc:>30s} {res.u[0]:>11.6f} {gap:>12s} {versus:>12.1e} {us:>8.2f}"
            )
    m1, m2, F = 1.0, 3.0, 2.0
    print(
        f"\nExpected (m1={m1}, m2={m2}, F={F}): rod → both accelerate at F/(m1+m2) = {F / (m1 + m2):.5f}; "
        f"servo → F/m2 = {F / m2:.5f} with servo force m1·F/m2 = {m1 * F / m2:.5f}."
    )
    print(
        "QP vs direct: the two routes' raw answers (no refinement step); vs reference: distance from the independent\n"
        "acceleration-space QP (gp.crosscheck: built from A, a0, J, phi, D alone, solved by a qpsolvers backend).\n"
        "µs/step: one compiled casadi call per step (Function.buffer), minimum over repeats."
    )
    print()
    _demo_scenes()
    _demo_figures(Path(args.out))
    return 0


#: Steps of compiled RK4 per scene in the demo (stiff or fast scenes need more).
_DEMO_STEPS = {"stiff-chain": 20_000, "andrews": 6_000}


def _demo_figures(out: Path) -> None:
    """The teaching pictures: rod vs servo, the realizability map, three realizations, the skate."""
    try:
        from . import plot

        plot._pyplot()
    except GaussppError as exc:  # matplotlib is an optional extra
        print(f"\n(no figures: {exc})")
        return
    from .simulation.simulate import simulate
    from .studies.figures import skate_runs, three_realizations_runs
    from .studies.realizability_map import realizability_grid

    out.mkdir(parents=True, exist_ok=True)
    runs = {}
    for realization in ("ideal", "servo"):
        scene = scenes.get("two-masses", realization=realization, k=3.0, v=0.5)
        runs[f"{'rod' if realization == 'ideal' else 'servo'}"] = simulate(
            scene.model, scene.q0, scene.v0, 4.0, method="rk4-compiled", dt=1e-3, solver="direct", record=10
        )
    figures = {
        "two_masses.png": lambda: plot.trajectory(runs, title="two masses: rod (ideal) vs follower force (servo)"),
        "realizability_map.png": lambda: plot.realizability_map(realizability_grid()),
        "three_realizations.png": lambda: plot.three_realizations(runs=three_realizations_runs()),
        "skate.png": lambda: plot.skate(runs=skate_runs()),
    }
    written = []
    for name, draw in figures.items():
        fig = draw()
        fig.savefig(out / name, dpi=100, bbox_inches="tight")
        plot._pyplot().close(fig)
        written.append(str(out / name))
    print(f"\nfigures written: {', '.join(written)}")


def _demo_scenes() -> None:
    """Every scene: compiled RK4 by QP and by the direct step, constraint residual, verification by (23)."""
    from .simulation.simulate import simulate
    from .verification.verify import verify

    print(
        f"Every scene, compiled RK4 with the direct step and with the Gauss QP ({qp.DEFAULT}), then verified by (23):\n"
    )
    header = (
        f"{'scene':19s} {'realizations':26s} {'T':>6s} {'steps':>6s} {'QP vs direct':>12s} {'|Φ|,|g| max':>11s} "
        f"{'energy bal.':>11s} {'(23) gap':>9s} {'motion':>6s} {'run ms':>7s}"
    )
    print(header)
    print("-" * len(header))
    for name in scenes.names("equality"):
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
    _demo_general()


def _demo_general() -> None:
    """Scenes without a closed-form step: contacts, bounded or extra actuators, redundant rows (general QP)."""
    from .simulation.simulate import simulate
    from .step.general import default_backend

    first = default_backend()  # daqp when installed, else OSQP: then there is no second backend to compare with
    second = None if first == "osqp" else "osqp"
    versus = f"{first} vs {second}" if second else "backends"
    compared = (
        f"{first}, compared with {second}" if second else f"{first} only; daqp not installed — `pip install daqp`"
    )
    print(f"\nBeyond closed forms — the general Gauss QP ({compared}), DOP853 rtol 1e-11:\n")
    header = (
        f"{'scene':19s} {'what':28s} {'T':>5s} {'events':>6s} {'saturated':>9s} {versus:>12s} "
        f"{'|Φ|,|g| max':>11s} {'energy bal.':>11s} {'vs exact':>9s} {'run ms':>7s}"
    )
    print(header)
    print("-" * len(header))
    for name in scenes.names("general"):
        scene = scenes.get(name)
        model = scene.model
        T = min(scene.t_end, 3.0)
        grid = np.linspace(0.0, T, 201)
        kwargs: dict[str, Any] = dict(lam0=scene.lam0, method="DOP853", rtol=1e-11, atol=1e-13, record=grid)
        if "stabilize" in scene.params:
            kwargs["stabilize"] = scene.params["stabilize"]
        elif model.bounded:
            kwargs["stabilize"] = "baumgarte"
        start = time.perf_counter()
        run = simulate(model, scene.q0, scene.v0, T, backend=f"qpsolvers:{first}", **kwargs)
        run_ms = (time.perf_counter() - start) * 1e3
        diff = "—"
        if second:
            other = simulate(model, scene.q0, scene.v0, T, backend=f"qpsolvers:{second}", **kwargs)
            on_grid = [np.flatnonzero(np.isin(tr.t, grid) & np.r_[np.diff(tr.t) > 0, True]) for tr in (run, other)]
            diff = f"{float(np.abs(run.q[on_grid[0]] - other.q[on_grid[1]]).max()):.1e}"
        redundant = run.solver.startswith("gauss-qp") and not (model.bounded or model.contacts or model.m > model.k)
        features = [
            f"{len(model.contacts)} contact(s)" if model.contacts else "",
            "bounded" if model.bounded else "",
            f"{model.m} actuators, {model.k} row(s)" if model.m > model.k else "",
            "redundant rows" if redundant else "",
        ]
        what = ", ".join(f for f in features if f)
        balance = np.abs(run.energy_balance())
        energy = f"{np.nanmax(balance):.1e}" if np.isfinite(balance).any() else "—"
        exact = "—"
        if scene.exact is not None:
            exact = f"{max(float(np.abs(scene.exact(t)[0] - q).max()) for t, q in zip(run.t, run.q, strict=True)):.1e}"
        saturated = f"{run.saturated.any(axis=1).mean():.0%}" if model.bounded else "—"
        print(
            f"{name:19s} {what:28s} {T:5.3g} {len(run.events):6d} {saturated:>9s} {diff:>12s} "
            f"{run.max_residual():11.1e} {energy:>11s} {exact:>9s} {run_ms:7.0f}"
        )
    print(
        "\nevents: impacts, lift-offs and touch-downs located by the integrator; saturated: share of samples with an "
        "actuator at its bound;"
    )
    if second:
        print(f"{versus}: largest difference of q on a common grid of 201 times (the two qpsolvers backends run here).")
    else:
        print(f"only {first} was run: daqp not installed — `pip install daqp` to compare two QP backends.")


def _print_study(rows: list[Any]) -> None:
    """The work-precision table and the fastest run per scene reaching 1e-10."""
    from .studies import report as study

    print(study.table(rows))
    print("\nFastest run reaching a final-state error ≤ 1e-10, per scene:")
    for scene, row in study.best_per_scene(rows).items():
        shown = (
            "none"
            if row is None
            else f"{row.method} · {row.solver} · {row.setting}: {row.final_error:.1e} in {row.wall_time:.4f} s"
        )
        print(f"  {scene:20s} {shown}")


def report(args: argparse.Namespace) -> int:
    """Work-precision study (or, with --stability, the stability study): table, CSV/JSON, plots."""
    from pathlib import Path

    from .studies import report as study

    out = Path(args.out)
    if args.stability:
        from .studies import stability

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
    _print_study(rows)
    files = study.write(rows, out)
    try:
        from . import plot

        files += plot.save_work_precision(rows, out)
    except GaussppError as exc:  # matplotlib missing: the table and data are still written
        print(f"(no plots: {exc})")
    print(f"\n{len(rows)} runs in {time.perf_counter() - start:.1f} s; written: {', '.join(str(f) for f in files)}")
    return 0


# -- run -----------------------------------------------------------------------------------------
def _simulate(
    args: argparse.Namespace, scene: scenes.Scene, label: str, *, every_step: bool = False
) -> tuple[Trajectory, float, float | None]:
    """Simulate ``scene`` as the command line says: the trajectory, the wall time in s, the ``dt`` used.

    Recording: about ``--samples`` intervals — uniform times by dense output for adaptive methods
    (or, with ``every_step``, every accepted step with ``T/samples`` as the largest step), every
    k-th step for fixed-step ones.
    """
    from .simulation.simulate import simulate

    meth = methods.get(args.method)
    t_end = scene.t_end if args.t_end is None else args.t_end
    solver, backend = getattr(args, "solver", None), getattr(args, "backend", None)
    if solver is None:  # CVODES differentiates the right-hand side: the direct step only
        solver = "direct" if meth.name == "cvodes" else "qp"
    elif meth.name == "cvodes" and solver != "direct":
        raise UsageError("--method cvodes needs --solver direct (CVODES differentiates the right-hand side)")
    stabilize = getattr(args, "stabilize", None)
    if stabilize is None:  # the scene's own drift control (a bounded servo's feedback), else none
        stabilize = scene.params.get("stabilize", "none")
    dt: float | None = args.dt
    record: Any = 1
    if meth.adaptive:
        if every_step:
            dt, record = dt or t_end / args.samples, 1
        else:
            record = np.linspace(0.0, t_end, args.samples + 1)
    else:
        dt = dt or t_end / 2000
        record = max(int(np.ceil(t_end / dt - 1e-9)) // args.samples, 1)
    if backend is not None:
        if solver == "direct":
            raise UsageError("--backend applies to --solver qp only")
        try:  # unknown or unavailable backends fail here, naming the valid ones (probing them prints banners)
            with redirect_stdout(io.StringIO()):
                qp.get(backend)
        except UnknownNameError as exc:
            raise UsageError(f"--backend {backend}: {exc}") from None
    with _Progress(label, enabled=not args.quiet), _warnings_as_lines():
        start = time.perf_counter()
        traj = simulate(
            scene.model,
            scene.q0,
            scene.v0,
            t_end,
            lam0=scene.lam0,
            dt=dt,
            method=meth.name,
            solver=solver,
            backend=backend,
            stabilize=None if stabilize == "none" else stabilize,
            rtol=args.rtol,
            atol=args.atol,
            record=record,
            throw=False,
        )
        wall = time.perf_counter() - start
    return traj, wall, dt


def _thin(traj: Trajectory, gap: float) -> Trajectory:
    """Drop samples closer than ``gap`` to the previous kept one (the last sample is kept).

    Adaptive integrators can end on a step of round-off size; such near-duplicate nodes spoil the
    spline that (23) differentiates. The two samples of a velocity jump (an impact: same time,
    before and after) are both kept: verification cuts the path there.
    """
    t, keep = traj.t, [0]
    for i in range(1, t.size):
        jump = t[i] <= t[i - 1]
        if jump and keep[-1] != i - 1:
            keep.append(i - 1)  # the sample just before the jump
        if jump or t[i] - t[keep[-1]] >= gap:
            keep.append(i)
    if t.size and keep[-1] != t.size - 1:
        keep[-1] = t.size - 1
    if len(keep) == t.size:
        return traj
    idx = np.array(keep)
    fields = {
        k: getattr(traj, k)[idx]
        for k in traj.__dataclass_fields__
        if isinstance(getattr(traj, k), np.ndarray) and getattr(traj, k).shape[:1] == t.shape
    }
    return replace(traj, **fields)


def _summary(scene: scenes.Scene, traj: Trajectory, wall: float, dt: float | None, rtol: float) -> list[str]:
    adaptive = methods.get(traj.method).adaptive
    setting = f"rtol {rtol:g}" if adaptive else f"dt {dt:g}"
    rows = [
        ("realizations", _realizations(scene.model)),
        ("method", f"{traj.method} ({setting}) · step by {traj.solver}"),
        ("status", traj.status + (f" — {_one_line(traj.message)}" if traj.message else "")),
        ("steps", f"{traj.steps} steps, {len(traj)} samples, {traj.rhs_evaluations} step evaluations, {wall:.3g} s"),
    ]
    if len(traj):
        rows.append(("time", f"t = {traj.t[0]:g} → {traj.t[-1]:.6g}"))
        rows.append(("final q", _vector(traj.q[-1])))
        rows.append(("final v", _vector(traj.v[-1])))
        if traj.lam.shape[1]:
            rows.append(("final λ", _vector(traj.lam[-1])))
        rows.append(("final u", _vector(traj.u[-1])))
        rows.append(("max |Φ|, |g|", f"{traj.max_residual():.2e}"))
        balance = np.abs(traj.energy_balance())
        rows.append(
            (
                "energy balance",
                f"{np.nanmax(balance):.2e} (largest |ΔE − W_reaction − W_forces|)"
                if np.isfinite(balance).any()
                else "— (the model does not know its energy or its forces' power)",
            )
        )
        if traj.margin.size:
            rows.append(("margin", f"{traj.margin.min():.4g} … {traj.margin.max():.4g} (realizability, σ_min of S)"))
        if traj.events:
            kinds = {
                k: sum(ev["kind"] == k for ev in traj.events) for k in dict.fromkeys(ev["kind"] for ev in traj.events)
            }
            rows.append(("events", ", ".join(f"{n} {k}" for k, n in kinds.items())))
        if traj.contact_force.shape[1]:
            rows.append(("contact force", f"{_vector(traj.contact_force[-1])} at the end"))
        if traj.saturated.size and traj.saturated.any():
            share = traj.saturated.any(axis=1).mean()
            rows.append(
                ("saturation", f"{share:.0%} of the samples, tracking error up to {traj.tracking_error.max():.3g}")
            )
        if scene.exact is not None and traj.success:
            q_ex, v_ex = scene.exact(float(traj.t[-1]))
            err = float(np.abs(np.concatenate([traj.q[-1] - q_ex, traj.v[-1] - v_ex])).max())
            rows.append(("vs exact", f"{err:.2e} (largest final-state error against the known motion)"))
    return [f"  {k:15s} {v}" for k, v in rows]


def _energy_balance(traj: Trajectory) -> np.ndarray:
    return traj.energy_balance() if len(traj) else np.zeros(0)


def _columns(traj: Trajectory) -> tuple[list[str], np.ndarray]:
    """The trajectory as named columns (for CSV)."""
    names, blocks = ["t"], [traj.t[:, None]]
    for key in ("q", "v", "lam", "a", "u", "residual", "g"):
        arr = getattr(traj, key)
        names += [f"{key}{i + 1}" for i in range(arr.shape[1])]
        blocks.append(arr)
    for key in ("margin", "compulsion", "energy", "work_reaction", "work_forces"):
        arr = getattr(traj, key)
        if arr.size == traj.t.size:
            names.append(key)
            blocks.append(arr[:, None])
    names.append("energy_balance")
    blocks.append(_energy_balance(traj)[:, None])
    return names, np.hstack(blocks) if traj.t.size else np.zeros((0, len(names)))


def _write_trajectory(traj: Trajectory, scene: scenes.Scene, params: dict[str, Any], out: Path) -> list[Path]:
    """``<scene>.npz`` (every array and the run's metadata), ``<scene>.csv`` and, with matplotlib, ``<scene>.png``."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        base = out / scene.name
        arrays = {k: np.asarray(getattr(traj, k)) for k in traj.__dataclass_fields__ if k not in ("status", "message")}
        meta = dict(scene=scene.name, params=json.dumps(params, default=repr), status=traj.status, message=traj.message)
        np.savez(base.with_suffix(".npz"), energy_balance=_energy_balance(traj), **arrays, **meta)  # type: ignore[arg-type]
        names, data = _columns(traj)
        np.savetxt(base.with_suffix(".csv"), data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
        files = [base.with_suffix(".npz"), base.with_suffix(".csv")]
    except OSError as exc:
        raise GaussppError(f"cannot write to {out}: {exc.strerror or exc}") from exc
    if len(traj):
        png = _plot_trajectory(traj, f"{_label(scene.name, params)} · {traj.method} · {traj.status}", base)
        if png is not None:
            files.append(png)
    return files


def _plot_trajectory(traj: Trajectory, title: str, base: Path) -> Path | None:
    """q(t) and v(t) as a PNG (``gausspp.plot.trajectory`` if there is one); None without matplotlib."""
    from . import plot

    try:
        plt = plot._pyplot()
    except GaussppError as exc:
        print(f"(no plot: {exc})")
        return None
    drawer = getattr(plot, "trajectory", None)
    if drawer is not None and "title" in inspect.signature(drawer).parameters:
        fig = drawer(traj, title=title)
    elif drawer is not None:
        fig = drawer(traj)
        fig.suptitle(title, fontsize=9)
    else:
        fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
        for ax, key, sym in ((axes[0], "q", "q"), (axes[1], "v", "v")):
            arr = getattr(traj, key)
            for i in range(arr.shape[1]):
                ax.plot(traj.t, arr[:, i], label=f"{sym}{i}")
            ax.set_ylabel(sym)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7, ncol=min(arr.shape[1], 6), loc="best")
        axes[1].set_xlabel("t")
        fig.suptitle(title, fontsize=9)
    path = base.with_suffix(".png")
    try:
        fig.savefig(path, dpi=110, bbox_inches="tight")
    except OSError as exc:
        raise GaussppError(f"cannot write {path}: {exc.strerror or exc}") from exc
    finally:
        plt.close(fig)
    return path


def run(args: argparse.Namespace) -> int:
    """Simulate one scene, print a summary, optionally write the trajectory (NPZ, CSV, PNG)."""
    params = _parse_params(args.scene, args.param)
    scene = _build(args.scene, params)
    traj, wall, dt = _simulate(args, scene, f"simulating {args.scene}")
    print(_label(scene.name, params))
    print("\n".join(_summary(scene, traj, wall, dt, args.rtol)))
    if args.out is not None:
        files = _write_trajectory(traj, scene, params, Path(args.out))
        print(f"  {'written':15s} {', '.join(str(f) for f in files)}")
    if not traj.success:
        raise GaussppError(f"the run failed: {_one_line(traj.message)}")
    return EXIT_OK


# -- verify -------------------------------------------------------------------------------------
def verify(args: argparse.Namespace) -> int:
    """Simulate a scene, then decide by (23) whether the path is a motion of its model (or of another)."""
    from .verification.verify import verify as check

    params = _parse_params(args.scene, args.param)
    check_params = _parse_params(args.scene, args.check_param, "--check-param")
    scene = _build(args.scene, params)
    model = _build(args.scene, {**params, **check_params}).model if check_params else scene.model
    traj, wall, dt = _simulate(args, scene, f"simulating {args.scene}", every_step=True)
    t_end = scene.t_end if args.t_end is None else args.t_end
    traj = _thin(traj, 0.05 * t_end / args.samples)
    print(f"path:     {_label(scene.name, params)} — {_realizations(scene.model)}")
    setting = f"rtol {args.rtol:g}" if methods.get(traj.method).adaptive else f"dt {dt:g}"
    reached = f" to t = {traj.t[-1]:.6g}" if len(traj) else ""
    print(f"          {traj.method} ({setting}), {len(traj)} samples{reached}, {wall:.3g} s")
    if not traj.success:
        raise GaussppError(f"the simulation failed, nothing to verify: {_one_line(traj.message)}")
    target = _label(scene.name, {**params, **check_params}) if check_params else "the same model"
    print(f"model:    {target} — {_realizations(model)}")
    with _Progress("verifying by (23)", enabled=not args.quiet), _warnings_as_lines():
        start = time.perf_counter()
        result = check(model, traj)
        wall = time.perf_counter() - start
    worst = int(np.argmax(np.abs(result.delta_x).max(axis=1))) if result.delta_x.size else 0
    lines = [
        ("relative gap", f"{result.relative_gap:.3e}  (on every other node: {result.coarse_relative_gap:.3e})"),
        ("tolerance", f"{result.tolerance:.3e}"),
        ("verification", f"{result.t.size} nodes, {wall:.3g} s"),
    ]
    if not result.is_motion:
        lines.append(("largest δx", f"at t = {result.t[worst]:.6g}: {_vector(result.delta_x[worst])}"))
    if result.pieces or result.skipped:
        lines += [("pieces", line) for line in result.message.splitlines()[1:]]
    for key, value in lines:
        print(f"  {key:14s} {value}")
    verdict = "a motion of the model" if result.is_motion else "NOT a motion of the model"
    reason = (
        "(relative gap ≤ tolerance)"
        if result.is_motion
        else "(relative gap > tolerance: the reaction does work on an admissible variation δx)"
    )
    print(f"verdict:  {verdict} {reason}")
    if args.expect is not None and (args.expect == "motion") != result.is_motion:
        raise GaussppError(f"expected {args.expect.replace('-', ' ')}, but the verdict is: {verdict}")
    return EXIT_OK


# -- scenes ---------------------------------------------------------------------------------------
def list_scenes(args: argparse.Namespace) -> int:
    """Every scene with a one-line description, or one scene's description and parameters."""
    if args.name is None:
        for name, line in scenes.describe().items():
            print(f"{name:20s} {line}")
        return EXIT_OK
    builder = scenes._builder(args.name)
    print(f"{args.name}: {inspect.getdoc(builder)}\n\nparameters (gausspp run {args.name} --param KEY=VALUE):")
    for key, param in _scene_parameters(args.name).items():
        ann = param.annotation
        kind = ann if isinstance(ann, str) else " | ".join(sorted(parameter_kinds(param))) or "any"
        print(f"  {key:16s} {kind:14s} default {param.default!r}")
    return EXIT_OK


# -- the parser ---------------------------------------------------------------------------------------
class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as one line (``gausspp: error: ...``) and exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"gausspp: error: {_one_line(message)} (see '{self.prog} --help')\n")


_SWEEP_ONLY = {
    "realizability": ("resolution",),
    "work-precision": ("scenes", "methods", "solvers", "full", "repeats"),
}


def sweep(args: argparse.Namespace) -> int:
    """A parameter sweep on local worker processes, appended to --out as it runs (resumable)."""
    from concurrent.futures import Executor, ProcessPoolExecutor

    for study, options in _SWEEP_ONLY.items():
        for option in options:
            if study != args.study and getattr(args, option) is not None:
                raise UsageError(f"--{option} applies to `gausspp sweep {study}` only")
    pool: Executor | None = ProcessPoolExecutor(args.workers) if args.workers > 1 else None
    try:
        if args.study == "realizability":
            return _sweep_realizability(args, pool or "serial")
        return _sweep_work_precision(args, pool or "serial")
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)


def _workers_text(args: argparse.Namespace) -> str:
    return f"{args.workers} worker{'s' if args.workers > 1 else ''}"


def _sweep_realizability(args: argparse.Namespace, executor: Any) -> int:
    from .studies import sweeps

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


def _sweep_work_precision(args: argparse.Namespace, executor: Any) -> int:
    from .studies import report as study
    from .studies import sweeps

    solvers = args.solvers
    if solvers:
        known = ["direct", *qp.names()]
        for solver in solvers:
            if solver not in known:
                raise UsageError(f"--solvers: {solver!r} is unknown; use {', '.join(known)}")
    repeats = 2 if args.repeats is None else args.repeats
    out = Path(args.out or "report")
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out for work-precision is a directory; {str(out)!r} is a file")
    log = out / "work_precision.jsonl"
    rows, res = sweeps.work_precision(
        args.scenes or None,
        args.methods or None,
        solvers or None,
        quick=not args.full,
        repeats=repeats,
        executor=executor,
        out=log,
        progress=not args.quiet,
    )
    _print_study(rows)
    files = [log, *study.write(rows, out)]
    try:
        from . import plot

        files += plot.save_work_precision(rows, out)
    except GaussppError as exc:  # matplotlib missing: the table and data are still written
        print(f"(no plots: {exc})")
    print(
        f"\n{len(rows)} runs; computed {res.computed} of {len(res)} tasks in {res.wall_time:.1f} s "
        f"({_workers_text(args)}{'; wall times measured side by side in the workers' if args.workers > 1 else ''}); "
        f"failed tasks: {len(res.errors)}"
    )
    print(f"written: {', '.join(str(f) for f in files)} (run again with the same --out to resume)")
    return 0 if res.ok else 1


def _common() -> _Parser:
    """Options every subcommand accepts too (after its name); absent there, the top-level value stands."""
    common = _Parser(add_help=False)
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show tracebacks")
    common.add_argument(
        "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress indication on stderr"
    )
    return common


def _positive(kind: type) -> Any:
    """An argparse type: a positive finite number of ``kind``."""

    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            value = None
        if value is None or not (value > 0 and np.isfinite(value)):
            raise argparse.ArgumentTypeError(
                f"expected a positive {'integer' if kind is int else 'number'}, got {text!r}"
            )
        return value

    return parse


def _simulation_options(p: argparse.ArgumentParser, rtol: float, samples: int) -> None:
    p.add_argument("scene", metavar="SCENE", choices=scenes.names(), help="a scene (see `gausspp scenes`)")
    p.add_argument(
        "-p",
        "--param",
        action="append",
        metavar="KEY=VALUE",
        help="a scene parameter, repeatable; VALUE is a Python literal (2.5, (1, 0, 0), None) or a word "
        "(servo); see `gausspp scenes SCENE` for the parameters",
    )
    p.add_argument(
        "--method",
        default="DOP853",
        choices=methods.names(),
        metavar="METHOD",
        help=f"integration method, one of {', '.join(methods.names())} (default: DOP853)",
    )
    p.add_argument("--t-end", type=_positive(float), metavar="T", help="final time (default: the scene's)")
    p.add_argument(
        "--dt",
        type=_positive(float),
        metavar="DT",
        help="step of fixed-step methods (default: T/2000); largest step of adaptive ones",
    )
    p.add_argument(
        "--rtol",
        type=_positive(float),
        default=rtol,
        metavar="R",
        help=f"relative tolerance of adaptive methods (default: {rtol:g})",
    )
    p.add_argument(
        "--atol",
        type=_positive(float),
        default=1e-12,
        metavar="A",
        help="absolute tolerance of adaptive methods (default: 1e-12)",
    )
    p.add_argument(
        "--samples",
        type=_positive(int),
        default=samples,
        metavar="N",
        help="record about N intervals: uniform times for adaptive methods, every k-th step otherwise "
        f"(default: {samples})",
    )


_EXIT_CODES = """\
exit codes: 0 success, 1 gausspp error or failed run, 2 bad command line."""

_EPILOG = (
    """\
examples:
  gausspp demo
  gausspp scenes two-masses
  gausspp run two-masses --param realization=servo --out results
  gausspp verify two-masses --param realization=ideal --check-param realization=servo

"""
    + _EXIT_CODES
)

_RUN = """\
Simulate SCENE and print a summary: status, steps, final state, constraint
residual, energy balance, realizability margin (and the error against the
exact motion where the scene knows it). With --out DIR, write DIR/SCENE.npz
(every array and the run's metadata), DIR/SCENE.csv and DIR/SCENE.png. A run
that fails midway still writes what it computed, then exits with 1.

examples:
  gausspp run two-masses --param realization=servo --param F=1
  gausspp run rigid-body-servo -p "n=(1, 0.2, 0)" --method rk4 --dt 1e-3 --out results
  gausspp run skate -p realization=vakonomic --solver direct"""

_VERIFY = """\
Simulate SCENE (DOP853 with tight tolerances by default), then decide by the
integral principle (23) whether the path is a motion of the scene's model —
or, with --check-param, of the same scene built with other parameters (another
realization of the same constraint, say). Prints the relative gap, the
tolerance and the verdict; exit 0 when the verification ran, whatever the
verdict, unless --expect says otherwise.

examples:
  gausspp verify two-masses
  gausspp verify two-masses --param realization=ideal --check-param realization=servo
  gausspp verify skate --check-param realization=vakonomic --expect not-motion"""


_DEMO = """\
One step of the two-mass and rigid-body scenes by the direct formula and by
the Gauss QP, with the time per step; then every scene simulated with both
step solvers, their agreement along the run, the constraint residual, the
energy balance and the verdict of the integral principle (23); then the scenes
only the general Gauss QP can solve (contacts, saturation, extra actuators,
redundant rows); and four teaching figures in --out.

example:
  gausspp demo --out demo-figures"""

_REPORT = """\
Error against run time: every scene (or --scenes) with every integration
method and step solver, scored against the scene's exact solution or a finer
reference by another method; wall time is the minimum of --repeats runs.
Prints the table and the fastest run per scene reaching 1e-10, and writes
CSV/JSON and one work-precision plot per scene to --out. With --stability,
runs the stability study instead (stiff chain, mass ratios, small margins,
long horizon, redundant rows, data off the constraint, crane at the vertical
rope), with a verdict per case; exit 1 if a verdict fails.

examples:
  gausspp report --scenes pendulum
  gausspp report --stability"""

_SWEEP = """\
Run a sweep on local worker processes. With --out every result is appended as
it arrives, and a second run with the same --out resumes: tasks already
recorded are not run again. For a dask cluster use gausspp.sweep from Python.

examples:
  gausspp sweep realizability --resolution 1 --out margins.jsonl
  gausspp sweep work-precision --out report
  gausspp sweep work-precision --scenes pendulum crane --methods rk4-compiled DOP853 --solvers direct"""


def _parser() -> argparse.ArgumentParser:
    common = _common()
    parser = _Parser(
        prog="gausspp",
        description="Constrained mechanics by Gauss's principle of least constraint, with servo-constraints.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks")
    parser.add_argument("--quiet", action="store_true", help="no progress indication on stderr")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    dem = sub.add_parser(
        "demo",
        parents=[common],
        help="the main job: every scene by QP and direct, a table, figures",
        description=_DEMO,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    dem.add_argument("--out", default="demo-figures", help="directory for the figures (default: demo-figures/)")
    dem.set_defaults(func=demo)
    sc = sub.add_parser(
        "scenes",
        parents=[common],
        help="list the scenes, or show one scene's parameters",
        description="List the scenes with a one-line description, or show one scene's description and parameters.",
    )
    sc.add_argument("name", nargs="?", metavar="SCENE", choices=scenes.names(), help="show this scene's parameters")
    sc.set_defaults(func=list_scenes)

    r = sub.add_parser(
        "run",
        parents=[common],
        help="simulate a scene: a summary, and the trajectory as files with --out",
        description=_RUN,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _simulation_options(r, rtol=1e-9, samples=500)
    r.add_argument(
        "--solver",
        choices=("qp", "direct"),
        help="each step by the Gauss QP or the direct formula (default: qp; direct for cvodes)",
    )
    r.add_argument(
        "--backend",
        metavar="B",
        help=f"QP backend for --solver qp (default: {qp.DEFAULT}); e.g. casadi:osqp, qpsolvers:daqp",
    )
    r.add_argument(
        "--stabilize",
        choices=("none", "project", "baumgarte"),
        default=None,
        help="drift control (default: the scene's own, e.g. the saturated crane's feedback; else none)",
    )
    r.add_argument("--out", metavar="DIR", help="write the trajectory to DIR (NPZ, CSV and, with matplotlib, PNG)")
    r.set_defaults(func=run)

    v = sub.add_parser(
        "verify",
        parents=[common],
        help="simulate a scene and decide by (23) whether the path is a motion",
        description=_VERIFY,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _simulation_options(v, rtol=1e-10, samples=400)
    v.add_argument(
        "-c",
        "--check-param",
        action="append",
        metavar="KEY=VALUE",
        help="build the model to check against with this parameter changed (repeatable)",
    )
    v.add_argument("--expect", choices=("motion", "not-motion"), help="exit with 1 if the verdict is not this")
    v.set_defaults(func=verify)

    rep = sub.add_parser(
        "report",
        parents=[common],
        help="error against run time for every scene, method and solver",
        description=_REPORT,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    rep.add_argument("--stability", action="store_true", help="run the stability study instead")
    rep.add_argument("--full", action="store_true", help="finer sweeps (and full-size stability cases)")
    rep.add_argument("--scenes", nargs="*", metavar="SCENE", choices=scenes.names(), help="only these scenes")
    rep.add_argument("--repeats", type=int, default=2, help="timing repeats (the minimum is kept)")
    rep.add_argument("--out", default="report", help="directory for CSV/JSON and plots (default: report/)")
    rep.add_argument("--verbose", action="store_true", help="progress on stderr")
    rep.set_defaults(func=report)

    swp = sub.add_parser(
        "sweep",
        parents=[common],
        help="a parameter sweep on all local cores, saved as it runs (resumable)",
        description=_SWEEP,
        epilog=_EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    swp.add_argument(
        "study",
        choices=("realizability", "work-precision"),
        help="realizability: the servo margin over the sphere of n; work-precision: the report's error against "
        "run time, one task per run",
    )
    swp.add_argument(
        "--workers",
        type=_positive(int),
        default=os.cpu_count() or 1,
        metavar="N",
        help="worker processes (default: all; 1 runs in this process)",
    )
    swp.add_argument(
        "--out",
        metavar="PATH",
        help="realizability: a JSON-lines FILE of results (appended; resumes). work-precision: a DIRECTORY "
        "(default: report/) for work_precision.jsonl (the resumable log), the CSV/JSON and the plots",
    )
    swp.add_argument(
        "--resolution",
        type=float,
        metavar="R",
        help="realizability: grid step in degrees (default: 2)",
    )
    swp.add_argument(
        "--scenes", nargs="+", metavar="SCENE", choices=scenes.names(), help="work-precision: only these scenes"
    )
    swp.add_argument(
        "--methods",
        nargs="+",
        metavar="METHOD",
        choices=methods.names(),
        help="work-precision: only these methods (default: rk4 rk4-compiled DOP853 Radau cvodes)",
    )
    swp.add_argument(
        "--solvers",
        nargs="+",
        metavar="SOLVER",
        help=f"work-precision: direct and/or QP backends (default: direct {qp.DEFAULT} casadi:osqp)",
    )
    swp.add_argument(
        "--full", action="store_true", default=None, help="work-precision: finer sweeps of steps and tolerances"
    )
    swp.add_argument(
        "--repeats", type=_positive(int), metavar="N", help="work-precision: timing repeats, the minimum is kept (2)"
    )
    swp.set_defaults(func=sweep)
    return parser


def _unknown_option(parser: argparse.ArgumentParser, argv: Sequence[str]) -> tuple[argparse.ArgumentParser, str] | None:
    """The first option in ``argv`` that neither ``parser`` nor the subcommand named in ``argv`` knows, with the
    parser it was given to. argparse reports a missing argument (``COMMAND``, ``SCENE``) before an unknown option,
    which misleads when the option is the mistake (``gausspp --bogus-flag``)."""
    commands = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), {})
    current = parser
    for token in argv:
        if token == "--":
            break
        if current is parser and token in commands:
            current = commands[token]
            continue
        if not token.startswith("-") or token == "-" or _is_number(token):
            continue
        known = [s for action in current._actions for s in action.option_strings]
        name = token.partition("=")[0]
        if token.startswith("--"):  # a long option, or an unambiguous abbreviation of one
            ok = any(k.startswith(name) for k in known if k.startswith("--"))
        else:  # a short option, with its value attached (-pKEY=VALUE) or not
            ok = any(token.startswith(k) for k in known if not k.startswith("--"))
        if not ok:
            return current, token
    return None


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gausspp`` command: the exit code (0 ok, 1 error or failed run, 2 usage)."""
    parser = _parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        unknown = _unknown_option(parser, argv)
        if unknown is not None:
            unknown[0].error(f"unrecognized arguments: {unknown[1]}")
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a usage error (2), already printed
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    try:
        return int(args.func(args))
    except UsageError as exc:
        if args.debug:
            raise
        print(f"gausspp: error: {_one_line(exc)} (see 'gausspp {args.command} --help')", file=sys.stderr)
        return EXIT_USAGE
    except GaussppError as exc:
        if args.debug:
            raise
        print(f"gausspp: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("gausspp: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # not foreseen by the library: still one line, the traceback with --debug
        if args.debug:
            raise
        print(
            f"gausspp: error: {type(exc).__name__}: {_one_line(exc)} (unexpected: run with --debug for the traceback)",
            file=sys.stderr,
        )
        return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
