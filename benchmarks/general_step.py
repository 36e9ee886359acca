"""The general Gauss step, whole calls: ``python benchmarks/general_step.py [--before REV]``.

Prints, measured in one run on this machine:

* ``model.step`` per call on every general scene (redundant rows, resting contacts, a saturated actuator, a
  bounce) beside the equality step's on the pendulum and the minimal four-bar, with the ratios the issue asks
  for (redundant four-bar / minimal four-bar's QP step; resting block and saturated crane / pendulum's QP step);
* whole ``gp.simulate`` runs: the redundant four-bar over 2 s (error against the minimal model), the saturated
  crane over 3 s, the block dropped on the floor over 3 s, the double parallelogram through its first collinear
  position, the spatial double parallelogram (revolute joints: 24 coordinates, 30 rows of rank 23, an
  overconstrained loop the size of Bricard's) swinging for 10 s — beside MuJoCo's four-bar (``connect``, RK4,
  dt = 1e-3, stiffest settings) and box drop when the peers extra is installed (``benchmarks/_mujoco_peers.py``);
* the ladder of double-parallelogram cells: ``model.step`` for N = 4 … 64 and its growth exponent, the first
  step's time (the Python step decides, the pattern compiles), beside MuJoCo's parallelogram ladder (its cells
  without the third bar: MuJoCo's soft ``connect`` rows need none).

``--before REV`` runs the same measurements on the package as it was at git revision ``REV`` (a temporary
worktree, in a second process; its ladder only up to ``--before-ladder``, default N = 8: before the sparse route
the build grew as N³, 150 s at N = 16) and prints both columns. Each time is the best of repeats (noise only adds
time); the machine is shared, so compare ratios taken in one run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _timing import best_ms  # noqa: E402

#: Ladder sizes (the issue's range: N = 4 … 64).
LADDER = (4, 8, 16, 32, 64)


def _best_us(fn: Any, repeats: int = 5, n: int = 200) -> float:
    fn()
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - start) / n)
    return best * 1e6


def measure(ladder_sizes: tuple[int, ...] = LADDER) -> dict[str, float]:
    """Every figure of this package (the one on ``sys.path``), by name."""
    import gausspp as gp
    from gausspp import scenes

    warnings.simplefilter("ignore")
    out: dict[str, float] = {}
    pend, mini, red = (
        scenes.get("pendulum"),
        scenes.get("four-bar-redundant", redundant=False),
        scenes.get("four-bar-redundant"),
    )
    out["step pendulum qp"] = _best_us(lambda: pend.model.step(0.0, pend.q0, pend.v0))
    out["step four-bar minimal qp"] = _best_us(lambda: mini.model.step(0.0, mini.q0, mini.v0))
    out["step four-bar-redundant"] = _best_us(lambda: red.model.step(0.0, red.q0, red.v0), n=50)
    crane, block = scenes.get("saturated-crane"), scenes.get("block-on-floor")
    tc = gp.simulate(crane.model, crane.q0, crane.v0, 3.0, record=np.linspace(0, 3, 301))
    i = int(np.flatnonzero(tc.saturated[:, 0])[0])
    out["step saturated-crane (saturated)"] = _best_us(lambda: crane.model.step(tc.t[i], tc.q[i], tc.v[i]), n=50)
    tb = gp.simulate(block.model, block.q0, block.v0, 3.0, record=np.linspace(0, 3, 31))
    out["step block-on-floor (resting)"] = _best_us(lambda: block.model.step(3.0, tb.q[-1], tb.v[-1]), n=50)
    bounce = scenes.get("bouncing-pendulum")
    out["step bouncing-pendulum"] = _best_us(lambda: bounce.model.step(0.0, bounce.q0, bounce.v0), n=50)
    grid = np.linspace(0.0, 2.0, 21)
    ref = gp.simulate(mini.model, mini.q0, mini.v0, 2.0, rtol=1e-13, atol=1e-13, record=grid)
    for label, kw in (("defaults", {}), ("cvodes-adams 1e-12", dict(method="cvodes-adams", rtol=1e-12, atol=1e-12))):
        try:
            run = gp.simulate(red.model, red.q0, red.v0, 2.0, record=grid, **kw)
        except Exception:  # a method this revision does not have
            continue
        out[f"simulate four-bar-redundant 2 s, {label} (ms)"] = best_ms(
            lambda kw=kw: gp.simulate(red.model, red.q0, red.v0, 2.0, record=grid, **kw), 2
        )
        out[f"  error vs minimal, {label}"] = float(np.abs(run.q - ref.q).max())
    out["simulate saturated-crane 3 s (ms)"] = best_ms(lambda: gp.simulate(crane.model, crane.q0, crane.v0, 3.0), 2)
    try:
        adams = dict(method="cvodes-adams", rtol=1e-9, atol=1e-9)
        gp.simulate(crane.model, crane.q0, crane.v0, 3.0, **adams)
        out["simulate saturated-crane 3 s, cvodes-adams 1e-9 (ms)"] = best_ms(
            lambda: gp.simulate(crane.model, crane.q0, crane.v0, 3.0, **adams), 2
        )
    except Exception:  # a method this revision does not have
        pass
    out["simulate block-on-floor 3 s (ms)"] = best_ms(lambda: gp.simulate(block.model, block.q0, block.v0, 3.0), 2)
    try:
        double = scenes.get("parallelogram", third_bar=True)
        from gausspp.scenes import parallelogram as P

        run = gp.simulate(double.model, double.q0, double.v0, 1.0, method="cvodes-adams", rtol=1e-10, atol=1e-10,
                          record=np.linspace(0, 1, 11))  # fmt: skip
        theta, omega = P.one_dof_reference(run.t, **double.params)
        qref = np.array([P.maximal_state(a, b, 0.0, 1, True)[0] for a, b in zip(theta, omega, strict=True)])
        out["double parallelogram 1 s, cvodes-adams 1e-10 (ms)"] = best_ms(
            lambda: gp.simulate(double.model, double.q0, double.v0, 1.0, method="cvodes-adams", rtol=1e-10,
                                atol=1e-10), 2)  # fmt: skip
        out["  error vs one-DOF reference (m)"] = float(np.abs(run.q - qref).max())
        try:  # an overconstrained spatial loop the size of Bricard's, swinging below its collinear positions
            from gausspp.scenes import spatial_parallelogram as SP

            swing = scenes.get("spatial-parallelogram", theta0=-np.pi / 2, omega0=1.0)
            run = gp.simulate(swing.model, swing.q0, swing.v0, 10.0, record=np.linspace(0, 10, 101))
            theta, omega = SP.one_dof_reference(run.t, **swing.params)
            qref = np.array([SP.maximal_state(a, b)[0] for a, b in zip(theta, omega, strict=True)])
            fresh = scenes.get("spatial-parallelogram", theta0=-np.pi / 2, omega0=1.0)  # nothing compiled yet
            start = time.perf_counter()
            gp.simulate(fresh.model, fresh.q0, fresh.v0, 10.0)
            out["spatial double parallelogram 10 s, defaults, first run (ms)"] = (time.perf_counter() - start) * 1e3
            out["spatial double parallelogram 10 s, defaults (ms)"] = best_ms(
                lambda: gp.simulate(swing.model, swing.q0, swing.v0, 10.0), 2
            )
            out["  error vs one-DOF reference (m) "] = float(np.abs(run.q - qref).max())
        except Exception as exc:  # a scene this revision does not have
            print(f"(spatial rows skipped: {type(exc).__name__}: {exc})", file=sys.stderr)
        try:  # through the collinear positions, 10 s (gausspp.simulation.crossing; earlier revisions stop there)
            import gausspp.simulation.crossing  # noqa: F401

            for name, third in (("A02 parallelogram", False), ("double parallelogram", True)):
                sc = scenes.get("parallelogram", third_bar=third)
                for label, tol in (("defaults", {}), ("rtol=atol=1e-12", dict(rtol=1e-12, atol=1e-12))):
                    run = gp.simulate(sc.model, sc.q0, sc.v0, 10.0, **tol)
                    theta, omega = P.one_dof_reference(run.t, **sc.params)
                    pairs = zip(theta, omega, strict=True)
                    qref = np.array([P.maximal_state(a, b, 0.0, 1, third)[0] for a, b in pairs])
                    key = f"{name} 10 s, {label}"
                    again = lambda sc=sc, tol=tol: gp.simulate(sc.model, sc.q0, sc.v0, 10.0, **tol)  # noqa: E731
                    out[f"{key} (ms)"] = best_ms(again, 2)
                    out[f"  collinear positions crossed, {key}"] = float(len(run.events))
                    out[f"  error vs one-DOF reference (m), {key}"] = float(np.abs(run.q - qref).max())
                    energy = run.energy
                    out[f"  energy drift (relative), {key}"] = float(np.ptp(energy) / np.abs(energy).max())
        except ImportError:
            pass
        for n in ladder_sizes:
            ladder = scenes.get("parallelogram", cells=n, third_bar=True)
            m = ladder.model
            start = time.perf_counter()
            m.step(0.0, ladder.q0, ladder.v0)
            out[f"first step ladder N={n} (s)"] = time.perf_counter() - start
            out[f"step ladder N={n}"] = _best_us(lambda m=m, s=ladder: m.step(0.0, s.q0, s.v0), n=20)
        if 32 in ladder_sizes:  # the same step generated as C (Model(codegen=True): c_code, kept on disk)
            ladder = scenes.get("parallelogram", cells=32, third_bar=True)
            m = gp.Model(ladder.model.mechanism, list(ladder.model.constraints), codegen=True)
            m.step(0.0, ladder.q0, ladder.v0)
            out["step ladder N=32, codegen"] = _best_us(lambda m=m, s=ladder: m.step(0.0, s.q0, s.v0), n=20)
    except Exception as exc:  # a scene this revision does not have
        print(f"(parallelogram rows skipped: {type(exc).__name__}: {exc})", file=sys.stderr)
    return out


def peers(ladder_sizes: tuple[int, ...] = LADDER) -> dict[str, float]:
    """MuJoCo's figures (empty without the peers extra)."""
    try:
        import _mujoco_peers as mj

        mj._mujoco()
    except Exception:
        return {}
    out = {"MuJoCo four-bar 2 s, RK4 dt 1e-3 (ms)": mj.four_bar()["wall_ms"]}
    out["MuJoCo box drop 3 s (ms)"] = mj.box_drop()["wall_ms"]
    for n in ladder_sizes:
        out[f"MuJoCo parallelogram ladder N={n} (µs/step)"] = mj.parallelogram_ladder(n)["step_us"]
    return out


def before(rev: str, ladder_sizes: str) -> dict[str, float]:
    """:func:`measure` on the package at ``rev`` (a temporary worktree, a second process)."""
    root = Path(subprocess.check_output(["git", "rev-parse", "--show-toplevel"], cwd=HERE, text=True).strip())
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "before"
        subprocess.run(["git", "worktree", "add", "-q", "--detach", str(tree), rev], cwd=root, check=True)
        try:
            env = {**os.environ, "PYTHONPATH": str(tree)}
            command = [sys.executable, __file__, "--json", "--ladder", ladder_sizes]
            text = subprocess.check_output(command, env=env, text=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=root, check=True)
    return json.loads(text.strip().splitlines()[-1])


def _exponent(sizes: list[int], times: list[float]) -> float:
    return float(np.polyfit(np.log(sizes), np.log(times), 1)[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", metavar="REV", help="also measure the package at this git revision")
    parser.add_argument("--json", action="store_true", help="print this package's figures as JSON (internal)")
    parser.add_argument("--ladder", default=",".join(map(str, LADDER)), help="ladder sizes, e.g. 4,8,16")
    parser.add_argument("--before-ladder", default="4,8", help="the earlier revision's ladder sizes")
    args = parser.parse_args()
    sizes = tuple(int(n) for n in args.ladder.split(","))
    if args.json:
        print(json.dumps(measure(sizes)))
        return
    now = measure(sizes)
    old = before(args.before, args.before_ladder) if args.before else {}
    mj = peers(sizes)
    print(f"{'figure':58s} {'now':>12s}" + (f" {'before':>12s}" if old else ""))
    for name, value in now.items():
        print(f"{name:58s} {value:12.4g}" + (f" {old.get(name, float('nan')):12.4g}" if old else ""))
    for name, value in mj.items():
        print(f"{name:58s} {value:12.4g}")
    print("\nratios (this run):")
    qp = now["step four-bar minimal qp"]
    print(f"  four-bar-redundant step / minimal four-bar QP step: {now['step four-bar-redundant'] / qp:.2f} (≤ 3)")
    for scene in ("block-on-floor (resting)", "saturated-crane (saturated)"):
        ratio = now[f"step {scene}"] / now["step pendulum qp"]
        print(f"  {scene} step / pendulum QP step: {ratio:.2f} (≤ 5)")
    if mj:
        for label in ("defaults", "cvodes-adams 1e-12"):
            key = f"simulate four-bar-redundant 2 s, {label} (ms)"
            if key in now:
                ratio = now[key] / mj[list(mj)[0]]
                print(f"  four-bar-redundant whole run ({label}) / MuJoCo's: {ratio:.2f} (issue 44: ≤ 1)")
        box = now["simulate block-on-floor 3 s (ms)"] / mj["MuJoCo box drop 3 s (ms)"]
        print(f"  block-on-floor whole run / MuJoCo's box drop: {box:.2f} (≤ 2)")
    ladder = [now.get(f"step ladder N={n}") for n in sizes]
    if len(sizes) > 1 and all(ladder):
        growth = _exponent(list(sizes), ladder)  # type: ignore[arg-type]
        print(f"  ladder step growth N^{growth:.2f} over N = {sizes[0]} … {sizes[-1]} (issue: ≤ N^1.3 over N = 4 … 64)")
        for n in sizes:
            key = f"MuJoCo parallelogram ladder N={n} (µs/step)"
            if key in mj:
                ratio = now[f"step ladder N={n}"] / mj[key]
                print(f"  ladder N={n} model.step / MuJoCo's step: {ratio:.2f}" + (" (issue: ≤ 2)" if n == 32 else ""))
        key = "MuJoCo parallelogram ladder N=32 (µs/step)"
        if "step ladder N=32, codegen" in now and key in mj:
            ratio = now["step ladder N=32, codegen"] / mj[key]
            print(f"  ladder N=32 model.step as C (codegen=True) / MuJoCo's step: {ratio:.2f}")


if __name__ == "__main__":
    main()
