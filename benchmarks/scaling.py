"""Growth with the number of bodies (issue 18), ``python benchmarks/scaling.py [--max-n N] [--figure PATH]``.

The problem: the ``planar-chain`` scene, ``N`` pinned links in maximal coordinates (``3N`` coordinates, ``2N``
ideal holonomic rows), the chain straight 0.3 rad below the horizontal at rest, ``dt = 1e-3``, 1000 steps
(``T = 1 s``), for ``N = 1, 2, 4, … 128``. Each ``N`` of each route runs in a child process of its own
(``--budget`` seconds, default 120, and ``--memory`` GB of address space): an ``N`` that exceeds either is
reported "over budget" and the larger ``N`` of that route are skipped.

Per ``N``, for ``solver="direct"`` and ``solver="qp"`` (``--solvers``):

- **build s** — constructing the model (``gp.scenes.get("planar-chain", N=N)``);
- **first s** — the first ``gp.simulate(..., method="rk4", lane="compiled", dt=1e-3)`` of 1000 steps: it builds and
  compiles the run's graph;
- **µs/step** — a second identical run, wall / 1000 (set-up and recording of every step included);
- **step only** — the same run recording its two ends only (``record=1000``), wall / 1000, best of three: the
  integration itself, what MuJoCo's ``mj_step`` column measures;
- **model.step µs** — one checked ``model.step`` call (``direct`` route only; ``benchmarks/_timing.py``'s minimum
  over repeats);
- **peak MB** — the child's peak resident memory (``ru_maxrss``);
- **violation** — ``max |g(q)|`` of the pins after the 1000 steps (no stabilization).

Beside them, when ``mujoco`` is importable (``pip install gausspp[peers]``), µs per ``mj_step`` (RK4,
``timestep = dt``, 1000 steps from the same state, minimum over repeats) of MuJoCo's same chain — per link a
body on slide x, slide z and hinge y joints from the world (maximal coordinates) held by ``connect`` equalities
at the pins with ``benchmarks/peers.py``'s stiffest settings — and of MuJoCo's hinge chain (nested bodies,
reduced coordinates, no constraint). ``tip`` is the largest distance, at ``T``, of the chain's free end from
the hinge chain's (gausspp direct and MuJoCo maximal): both integrate the same motion.

``--codegen`` runs the compiled lane's step as C (``gp.Model(..., codegen=True)``, :mod:`gausspp.c_code`): the
first call then includes the C compiler's time, and the library is kept on disk.

``--mechanism ladder`` times the closed-loop ``planar-ladder`` scene instead (``N`` parallelogram four-bars stacked:
two rails and a rung per level, ``9N`` coordinates, ``8N`` rows; gausspp only).

Printed: the table, the growth exponents (least squares of ``log time`` on ``log N`` over the ``N ≥ 8`` that
ran) and, with ``--figure PATH`` and matplotlib, a log–log figure of the per-step times.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from _figures import headless_pyplot
from _timing import best_us

NS = (1, 2, 4, 8, 16, 32, 64, 128)
DT, STEPS = 1e-3, 1000
CHAIN = dict(m=1.0, L=1.0, g=9.81, theta0=-0.3, t_end=STEPS * DT)
#: mechanism → (scene, its parameters): the chain, and a closed-loop one (a ladder of parallelogram four-bars)
MECHANISMS: dict[str, tuple[str, dict[str, float]]] = {
    "chain": ("planar-chain", CHAIN),
    "ladder": ("planar-ladder", dict(m=1.0, L=1.0, W=1.0, g=9.81, theta0=-1.0, t_end=STEPS * DT)),
}
FIT_FROM = 8  # growth exponents over N ≥ FIT_FROM


# ------------------------------------------------------------------------------------------ in the child


def peak_mb() -> float:
    """The process's peak resident memory in MB (``ru_maxrss`` is in kB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def timed(call: Callable[[], Any]) -> tuple[float, Any]:
    start = time.perf_counter()
    out = call()
    return time.perf_counter() - start, out


def free_end(q: np.ndarray, L: float) -> np.ndarray:
    """The last link's bottom end from maximal coordinates ``q = (x, z, θ)ᵢ``."""
    x, z, theta = q[-3:]
    return np.array([x + 0.5 * L * math.cos(theta), z + 0.5 * L * math.sin(theta)])


def gausspp_child(N: int, solver: str, mechanism: str, route: str, codegen: bool = False) -> dict[str, Any]:
    """Build, first run, second run, a run recording its ends only, one ``model.step`` (direct), violation and
    the free end at ``T``; the step's ``route`` ("auto", "dense" or "sparse")."""
    import gausspp as gp

    name, params = MECHANISMS[mechanism]

    def build_model() -> Any:
        scene = gp.scenes.get(name, N=N, **params)
        m = scene.model
        if route == "auto" and not codegen:
            return scene, m
        return scene, gp.Model(m.mechanism, list(m.constraints), route=route, codegen=codegen)

    build, (scene, model) = timed(build_model)
    q0, v0 = scene.q0, scene.v0

    def run(record: int = 1) -> Any:
        return gp.simulate(
            model, q0, v0, CHAIN["t_end"], dt=DT, method="rk4", lane="compiled", solver=solver, record=record
        )

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        first, _ = timed(run)
        second, traj = timed(run)
        ends = min(timed(lambda: run(STEPS))[0] for _ in range(3))
        out = dict(build_s=build, first_s=first, per_step_us=second / STEPS * 1e6, step_only_us=ends / STEPS * 1e6)
        out["route"] = traj.route
        if solver == "direct":
            lam = np.zeros(model.n_lam)
            out["step_us"] = best_us(lambda: model.step(0.0, q0, v0, lam, solver="direct"), 0.2, 3)
    out["violation"] = float(np.abs(traj.g[-1]).max())
    out["tip"] = free_end(traj.q[-1], CHAIN["L"]).tolist()
    return out


STIFFEST = 'solref="0.002 1" solimp="0.9999 0.9999 0.001 0.5 2"'  # peers.py's: time constant 2·dt


def mjcf(bodies: str, equalities: str = "") -> str:
    g = CHAIN["g"]
    head = f'<compiler angle="radian"/><option timestep="{DT}" integrator="RK4" gravity="0 0 {-g}"/>'
    return f"<mujoco>{head}<worldbody>{bodies}</worldbody><equality>{equalities}</equality></mujoco>"


def inertial(pos: float = 0.0) -> str:
    m, L = CHAIN["m"], CHAIN["L"]
    inertia = m * L * L / 12.0
    return f'<inertial pos="{pos} 0 0" mass="{m}" diaginertia="{inertia} {inertia} {inertia}"/>'


def maximal_chain(N: int) -> str:
    """Per link a body at its centre on slide x, slide z, hinge y from the world; ``connect`` at the pins.

    A body's ``x`` axis lies along its link (a rotation by ``−θ0`` about ``y`` maps ``x`` to
    ``(cos θ0, 0, sin θ0)``); a ``connect`` pins the anchor (the link's top) to where it is at ``qpos0``
    on the previous body (its bottom), or on the world (the origin) for the first link.
    """
    L, theta0 = CHAIN["L"], CHAIN["theta0"]
    joints = '<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/><joint type="hinge" axis="0 1 0"/>'
    bodies, pins = [], []
    for i in range(N):
        x, z = (i + 0.5) * L * math.cos(theta0), (i + 0.5) * L * math.sin(theta0)
        bodies.append(f'<body name="b{i}" pos="{x} 0 {z}" euler="0 {-theta0} 0">{joints}{inertial()}</body>')
        other = f' body2="b{i - 1}"' if i else ""
        pins.append(f'<connect body1="b{i}"{other} anchor="{-0.5 * L} 0 0" {STIFFEST}/>')
    return mjcf("".join(bodies), "".join(pins))


def hinge_chain(N: int) -> str:
    """Nested bodies, each on a hinge y at its top end (the previous link's bottom): reduced coordinates."""
    L, theta0 = CHAIN["L"], CHAIN["theta0"]
    body = ""
    for i in reversed(range(N)):
        place = f'pos="0 0 0" euler="0 {-theta0} 0"' if i == 0 else f'pos="{L} 0 0"'
        body = f'<body name="b{i}" {place}><joint type="hinge" axis="0 1 0"/>{inertial(0.5 * L)}{body}</body>'
    return mjcf(body)


def mujoco_tip(mujoco: Any, model: Any, data: Any, N: int, offset: float) -> list[float]:
    """The last body's point ``(offset, 0, 0)`` in the x–z plane, at the state reached."""
    mujoco.mj_forward(model, data)
    body = model.body(f"b{N - 1}").id
    point = data.xpos[body] + data.xmat[body].reshape(3, 3) @ np.array([offset, 0.0, 0.0])
    return [float(point[0]), float(point[2])]


def pin_gap(model: Any, data: Any, N: int) -> float:
    """The largest pin gap of the maximal chain: each top from the previous bottom (the origin for the first)."""
    L, gap, previous = CHAIN["L"], 0.0, np.zeros(3)
    for i in range(N):
        centre, axis = data.xpos[model.body(f"b{i}").id], data.xmat[model.body(f"b{i}").id].reshape(3, 3)[:, 0]
        gap = max(gap, float(np.abs(centre - 0.5 * L * axis - previous).max()))
        previous = centre + 0.5 * L * axis
    return gap


def mujoco_child(N: int) -> dict[str, Any]:
    """µs per ``mj_step`` of both MuJoCo chains, the free end at ``T`` and the maximal chain's pin gap."""
    import mujoco

    out: dict[str, Any] = {"version": mujoco.__version__}
    for key, xml, offset in (("maximal", maximal_chain(N), 0.5), ("hinge", hinge_chain(N), 1.0)):
        model = mujoco.MjModel.from_xml_string(xml)
        data = mujoco.MjData(model)

        def run(model: Any = model, data: Any = data) -> None:
            mujoco.mj_resetData(model, data)
            for _ in range(STEPS):
                mujoco.mj_step(model, data)

        out[f"{key}_us"] = best_us(run, 0.3, 3) / STEPS
        run()
        out[f"{key}_tip"] = mujoco_tip(mujoco, model, data, N, offset * CHAIN["L"])
        if key == "maximal":
            out["maximal_violation"] = pin_gap(model, data, N)
    return out


def child(
    route: str, N: int, memory_gb: float, mechanism: str, step_route: str = "auto", codegen: bool = False
) -> None:
    """Run one route at one ``N`` and print its figures as one JSON line."""
    limit = int(memory_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    out = mujoco_child(N) if route == "mujoco" else gausspp_child(N, route, mechanism, step_route, codegen)
    out["peak_mb"] = peak_mb()
    print(json.dumps(out))


# ----------------------------------------------------------------------------------------- in the parent


def spawn(route: str, N: int, args: argparse.Namespace) -> dict[str, Any]:
    """One child; ``{"status": "over budget" | "out of memory" | "failed: …"}`` when it gives no figures."""
    command = [sys.executable, __file__, "--child", route, str(N), "--memory", str(args.memory)]
    command += ["--mechanism", args.mechanism, "--route", args.route] + (["--codegen"] if args.codegen else [])
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=args.budget)
    except subprocess.TimeoutExpired:
        return {"status": "over budget"}
    if done.returncode == 0:
        return {"status": "ok", **json.loads(done.stdout.strip().splitlines()[-1])}
    if "MemoryError" in done.stderr or "bad_alloc" in done.stderr or done.returncode == -9:
        return {"status": "out of memory"}
    return {"status": f"failed: {(done.stderr.strip().splitlines() or ['?'])[-1][:80]}"}


def measure(routes: list[str], args: argparse.Namespace) -> dict[str, dict[int, dict[str, Any]]]:
    """Every route at every ``N`` up to ``--max-n``; after a route's first failure its larger ``N`` are skipped.

    A child is not started when the geometric extrapolation of the last two children's walls,
    ``wall(N) · wall(N) / wall(N/2)``, exceeds the budget (reported "over budget" with the prediction):
    on a shared machine a run known to be killed is not worth its minutes.
    """
    results: dict[str, dict[int, dict[str, Any]]] = {route: {} for route in routes}
    for route in routes:
        walls: list[float] = []
        for N in (n for n in NS if n <= args.max_n):
            predicted = walls[-1] ** 2 / walls[-2] if len(walls) >= 2 else 0.0
            if predicted > args.budget:
                result = {"status": f"over budget (predicted {predicted:.0f} s)"}
            else:
                wall, result = timed(lambda: spawn(route, N, args))  # noqa: B023
                walls.append(wall)
            results[route][N] = result
            print(f"  {route:7s} N = {N:4d}: {result['status']}", file=sys.stderr, flush=True)
            if result["status"] != "ok":
                break
    return results


def cell(result: dict[str, Any] | None, key: str, fmt: str) -> str:
    if result is None:
        return "skipped"
    if result["status"] != "ok":
        return "over budget" if result["status"].startswith("over") else result["status"][:12]
    value = result.get(key)
    return "" if value is None else format(value, fmt)


def tip_error(results: dict[str, dict[int, dict[str, Any]]], N: int) -> str:
    """The free end's distance from MuJoCo's hinge chain at ``T``: gausspp direct, MuJoCo maximal."""
    mj, gp_ = results.get("mujoco", {}).get(N), results.get("direct", {}).get(N)
    if not (mj and mj["status"] == "ok"):
        return ""
    hinge = np.array(mj["hinge_tip"])
    parts = [np.abs(np.array(r["tip"]) - hinge).max() if r and r["status"] == "ok" else math.nan for r in (gp_,)]
    parts.append(float(np.abs(np.array(mj["maximal_tip"]) - hinge).max()))
    return " / ".join("—" if math.isnan(p) else f"{p:.0e}" for p in parts)


COLUMNS = [  # (header, route, key, format, width)
    ("build s", "direct", "build_s", ".3f", 8),
    ("first s", "direct", "first_s", ".2f", 8),
    ("direct µs/step", "direct", "per_step_us", ".1f", 14),
    ("direct step only", "direct", "step_only_us", ".1f", 16),
    ("model.step µs", "direct", "step_us", ".1f", 13),
    ("peak MB", "direct", "peak_mb", ".0f", 8),
    ("violation", "direct", "violation", ".0e", 9),
    ("qp first s", "qp", "first_s", ".2f", 10),
    ("qp µs/step", "qp", "per_step_us", ".1f", 12),
    ("qp step only", "qp", "step_only_us", ".1f", 12),
    ("qp peak MB", "qp", "peak_mb", ".0f", 10),
    ("MuJoCo max µs", "mujoco", "maximal_us", ".1f", 13),
    ("MuJoCo gap", "mujoco", "maximal_violation", ".0e", 10),
    ("MuJoCo hinge µs", "mujoco", "hinge_us", ".1f", 15),
]


def print_table(results: dict[str, dict[int, dict[str, Any]]], args: argparse.Namespace) -> None:
    columns = [c for c in COLUMNS if c[1] in results]
    print(f"{'N':>4s} | " + " | ".join(f"{h:>{w}s}" for h, _, _, _, w in columns) + " | tip vs hinge (gp / MuJoCo max)")
    print("-" * (7 + sum(w + 3 for *_, w in columns) + 30))
    for N in (n for n in NS if n <= args.max_n):
        row = [f"{cell(results[r].get(N), k, f):>{w}s}" for _, r, k, f, w in columns]
        print(f"{N:4d} | " + " | ".join(row) + f" | {tip_error(results, N)}")
    for route, by_n in results.items():
        for N, result in by_n.items():
            if result["status"] != "ok":
                print(f"  {route} at N = {N}: {result['status']}; larger N skipped")


def exponent(results: dict[int, dict[str, Any]], key: str) -> tuple[float, int]:
    """Least-squares slope of ``log value`` on ``log N`` over the ``N ≥ FIT_FROM`` that ran, and how many."""
    points = [(N, r[key]) for N, r in results.items() if N >= FIT_FROM and r["status"] == "ok" and key in r]
    if len(points) < 2:
        return math.nan, len(points)
    n, value = np.log(np.array(points, dtype=float)).T
    return float(np.polyfit(n, value, 1)[0]), len(points)


SERIES = [  # (label, route, key): the fitted and plotted series
    ("gausspp direct per step", "direct", "per_step_us"),
    ("gausspp direct step only", "direct", "step_only_us"),
    ("gausspp qp per step", "qp", "per_step_us"),
    ("gausspp qp step only", "qp", "step_only_us"),
    ("gausspp model.step (direct)", "direct", "step_us"),
    ("gausspp first call (compile)", "direct", "first_s"),
    ("MuJoCo maximal chain per step", "mujoco", "maximal_us"),
    ("MuJoCo hinge chain per step", "mujoco", "hinge_us"),
]


def print_exponents(results: dict[str, dict[int, dict[str, Any]]]) -> None:
    print(f"\ngrowth exponents (time ∝ N^p, least squares on log–log over N ≥ {FIT_FROM} that ran):")
    for label, route, key in SERIES:
        if route in results:
            p, count = exponent(results[route], key)
            print(f"  {label:32s} p = {p:5.2f}  ({count} points)" if count >= 2 else f"  {label:32s} (too few N)")


def figure(results: dict[str, dict[int, dict[str, Any]]], path: str, title: str) -> None:
    """Per-step time against N, log–log (matplotlib, optional)."""
    plt = headless_pyplot()
    if plt is None:
        return
    from gausspp.plot import palette

    fig, ax = plt.subplots(figsize=(7, 5))
    for i, (label, route, key) in enumerate(SERIES):
        points = sorted((N, r[key]) for N, r in results.get(route, {}).items() if r["status"] == "ok" and key in r)
        if points and key != "first_s":
            style = "s--" if label.startswith("MuJoCo") else "o-"  # the peer dashed
            ax.loglog(*zip(*points, strict=True), style, color=palette(i), label=label)
    ax.set(
        xlabel="N links (levels of the ladder)",
        ylabel="wall time per step (µs)",
        title=f"scene {title} (links m = 1 kg, L = 1 m): RK4, dt = {DT:g} s, {STEPS} steps",
    )
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    print(f"figure written to {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-n", type=int, default=128, help="largest N (default 128)")
    parser.add_argument("--budget", type=float, default=120.0, help="seconds per N and route (default 120)")
    parser.add_argument("--memory", type=float, default=8.0, help="GB of address space per child (default 8)")
    parser.add_argument("--solvers", default="direct,qp", help="gausspp step solvers, comma-separated")
    parser.add_argument("--figure", metavar="PATH", help="per-step time against N, log–log (needs matplotlib)")
    parser.add_argument("--mechanism", choices=list(MECHANISMS), default="chain", help="default: chain")
    parser.add_argument(
        "--route", choices=["auto", "dense", "sparse"], default="auto", help="the step's route (default auto)"
    )
    parser.add_argument("--codegen", action="store_true", help="the compiled lane's step as C (Model(codegen=True))")
    parser.add_argument("--child", nargs=2, metavar=("ROUTE", "N"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]), args.memory, args.mechanism, args.route, args.codegen)
        return
    routes = [s.strip() for s in args.solvers.split(",") if s.strip()]
    try:
        import mujoco  # noqa: F401

        if args.mechanism == "chain":  # MuJoCo's models are the chain's
            routes.append("mujoco")
    except ImportError:
        print("mujoco is not installed (pip install gausspp[peers]): its columns are skipped")
    results = measure(routes, args)
    scene = MECHANISMS[args.mechanism][0]
    print(f"\n{scene}, rk4 compiled, dt = {DT:g}, {STEPS} steps; budget {args.budget:g} s per N and route")
    print_table(results, args)
    print_exponents(results)
    if args.figure:
        figure(results, args.figure, MECHANISMS[args.mechanism][0])


if __name__ == "__main__":
    main()
