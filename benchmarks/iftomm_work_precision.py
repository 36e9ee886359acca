"""Work-precision of the IFToMM multibody benchmark problems: gausspp beside MuJoCo and Exudyn, in one run.

    .venv/bin/python benchmarks/iftomm_work_precision.py [--quick] [--figure PATH] [--problems A01,A04]

Issue 44, item 1. Each problem is written as a user writes it, run from its initial state over ``T = 10`` s
(``--quick``: 2 s and fewer settings; A03 always over its published 0.03 s), and scored by the benchmark's output
quantity against an independent reference — never against the run being scored. The error of a run is the largest
difference from the reference over the record grid ``t = 0, 0.1, …, T`` (A03: at ``t = 0.03``).

* **A01 simple pendulum** — the ``pendulum`` scene (a planar body, ``m = 1``, ``Ic = 0.01``, its centre of mass
  ``L = 1`` from a pin, released level with it at rest, ``g = 9.81``): two holonomic rows on ``(x, z, φ)``. Output:
  the centre of mass ``(x, z)`` (m, the Euclidean distance). Reference: the 1-DOF equation about the pin,
  ``(Ic + m L²) φ̈ = −m g L cos φ``, by scipy's DOP853 at ``rtol = atol = 1e-13`` (the scene's ``exact``).
* **A02 parallelogram four-bar** — ``four_bar()`` of examples/bodies_and_joints.py (three bars of 1 m and 1 kg,
  ground pins 1 m apart, cranks vertical, the first crank turning at −1 rad/s): 9 maximal coordinates, 8 rows; the
  bars fall in line twice a turn. Output: the first crank's angle (rad). Reference:
  ``gausspp.scenes.parallelogram.one_dof_reference`` — ``I θ̈ = −G cos θ`` by scipy at 1e-13.
* **A03 Andrews' squeezing mechanism** — the ``andrews`` scene (7 angles, 6 rows, the test set's model), over its
  published horizon 0.03 s (there is no reference further on). Output: the 7 angles at 0.03 s (rad, largest
  difference). Reference: ``andrews.reference(which="converged")``, an extended-precision solution of the published
  formulas by mpmath's Taylor integrator (benchmarks/andrews_converged.py; the published PSIDE values agree with it to
  their stated 1.4e-9).
* **A04 Bricard's mechanism** — ``bricard()`` of examples/bodies_and_joints.py (five rods of 1 m and 1 kg on the
  edges of a cube, six hinges: 35 coordinates, 30 rows of rank 29), released from rest; and the same machine read
  from MJCF by ``gp.from_mjcf(bricard_mjcf(1e-3))`` — MuJoCo's joint coordinates, five hinges closed by two
  ``connect`` rows, 5 coordinates and 6 rows. Output: the point P3 (the hinge between rods 3 and 4, at ``(1, −1, 1)``
  initially; m, Euclidean distance). Reference: no closed form; a gausspp run at ``rtol = atol = 1e-13`` in the
  *other* coordinates — for every row the joint-coordinate run (``from_mjcf``), for the ``from_mjcf`` rows the
  maximal-coordinate run. The two references share gausspp's Gauss step but no model, coordinates or constraint rows;
  their difference is printed (the floor of the A04 errors, a dotted line in the figure: an error below it is not
  resolved).
* **A05 flyball governor** — skipped: examples/bodies_and_joints.py has the machine (41 rows of rank 35, a prescribed
  spindle speed), but no independent reference of its motion exists here (no closed form, no second model in other
  coordinates, no MJCF), and a spindle driven at a prescribed speed is a servo-constraint neither peer model has.

Settings and what is timed (each row is one whole run over ``T``, warm: a first call before the timed ones, then the
best of 3 — of 1 when the first call took more than 5 s — ``benchmarks/_timing.py``'s ``best_ms``; the column ``1st``
is the first call, compiling included where a code compiles):

* **gausspp** — ``gp.simulate(model, q0, v0, T, record=grid)``, whole call, at its defaults (DOP853, ``rtol = 1e-10``)
  and at ``rtol`` = 1e-4, 1e-6, 1e-8, 1e-10, 1e-12 (``atol`` following ``rtol``, gausspp's default); ``throw=False``,
  so a failed run is kept as a row with its status, where it stopped and why. Status: the trajectory's
  (``"success"``, ``"drifted"``, ``"failed"``). Families: ``gausspp`` (``gp.Multibody`` or the scene) and
  ``gausspp from_mjcf`` (A02: the MJCF of benchmarks/_mujoco_peers.py's one-cell ladder; A04: ``bricard_mjcf``).
* **MuJoCo** (optional) — RK4 at ``dt`` = 1e-2, 1e-3, 2e-4, 1e-4, equalities at the stiffest softness it allows
  (``solref`` time constant ``2 dt``, ``solimp`` 0.9999: benchmarks/_mujoco_peers.py's ``stiffest``). A01: the body on
  a free joint pinned by a ``connect`` (family ``MuJoCo``), and on a hinge at the pin (``MuJoCo hinge``: no
  constraint at all); A02: the hinge chain closed by a ``connect`` (``_mujoco_peers.ladder_mjcf(1)``); A04:
  ``bricard_mjcf(dt)``. Timed: the reset, the initial state and ``mj_step(model, data, n)`` between the record times
  (the positions copied there); the outputs are computed afterwards from the copies by ``mj_kinematics``. Status:
  ``"success"`` if the state stays finite.
* **Exudyn** (optional) — its default dynamic solver, generalized-α (index 3, spectral radius 0.9, Newton on its
  defaults), at ``h`` = 1e-2, 1e-3, 2e-4, 1e-4, 5e-5; timed: ``mbs.SolveDynamic`` whole (the system assembled once
  before), outputs by an in-memory body sensor every 0.1 s, no solution file. A01 and A02 as 2-D rigid bodies and
  ``ObjectJointRevolute2D``; A04 as 3-D rigid bodies (Euler parameters) and ``CreateRevoluteJoint`` — 30 rows of rank
  29 — with Exudyn's own recipe for redundant constraints: the dense solver with ``ignoreSingularJacobian`` (full
  pivoting, the redundant rows resolved by least squares); A02 takes the same recipe for its collinear positions. A03
  is not built in Exudyn nor in MuJoCo (seven bodies in three loops and a spring: too much work for this benchmark).
  Status: ``"success"`` if ``SolveDynamic`` reached ``T``.

Printed: per problem the rows (code, setting, wall ms, first call ms, steps, error, status), then for each problem
and code the fastest wall reaching the errors 1e-3, 1e-6 and 1e-9 (runs that reached ``T``: ``"success"`` or
``"drifted"``).
With ``--figure PATH``: one panel per problem, wall time (log) against error (log), one line per code; the docs'
figure is docs/work_precision_iftomm.png. A missing peer is said and its rows skipped.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import _mujoco_peers as mjp
import numpy as np
from _figures import headless_pyplot
from _optional import peer
from _timing import best_ms

import gausspp as gp
from gausspp.scenes import andrews, pendulum
from gausspp.scenes import parallelogram as P

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("bodies_and_joints", ROOT / "examples" / "bodies_and_joints.py")
assert _spec is not None and _spec.loader is not None
example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(example)

G = 9.81
RTOLS = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]
DTS = [1e-2, 1e-3, 2e-4, 1e-4]
HS = [1e-2, 1e-3, 2e-4, 1e-4, 5e-5]
QUICK_RTOLS, QUICK_DTS, QUICK_HS = [1e-6, 1e-10], [1e-2, 1e-3], [1e-2, 1e-3]
LEVELS = [1e-3, 1e-6, 1e-9]
FLOORS: dict[str, float] = {}  # a problem's reference floor: how far its two references differ (A04)
SLOW_S = 5.0  # a first call longer than this is timed once more, not three times


@dataclass
class Row:
    problem: str
    code: str  # the family: one line in the figure
    setting: str
    wall_ms: float = math.nan
    first_ms: float = math.nan
    error: float = math.nan
    status: str = ""
    note: str = ""
    steps: int = 0  # gausspp: its accepted steps; MuJoCo, Exudyn: T / dt


def timed(fn: Callable[[], Any]) -> tuple[Any, float, float]:
    """``(result, wall ms, first call ms)``: the first call (compiling included where a code compiles) gives the
    result; then ``best_ms`` — one more warm-up call, the best of 3 — or, when the first call took more than
    ``SLOW_S``, one more call alone."""
    start = time.perf_counter()
    result = fn()
    first = time.perf_counter() - start
    if first > SLOW_S:
        start = time.perf_counter()
        fn()
        return result, (time.perf_counter() - start) * 1e3, first * 1e3
    return result, best_ms(fn, 3), first * 1e3


def progress(row: Row) -> Row:
    print(
        f"  … {row.problem} {row.code:20s} {row.setting:12s} {row.wall_ms:10.1f} ms {row.error:9.1e} {row.status}",
        file=sys.stderr,
        flush=True,
    )
    return row


# ------------------------------------------------------------------------------------------------- gausspp


def gausspp_rows(
    problem: str,
    code: str,
    model: gp.Model,
    q0: np.ndarray,
    v0: np.ndarray,
    t_end: float,
    grid: np.ndarray,
    error: Callable[[gp.Trajectory], float],
    rtols: list[float],
) -> list[Row]:
    """``gp.simulate`` at the defaults and at each ``rtol``, whole call, warm; failed runs kept."""
    rows = []
    for rtol in [None, *rtols]:
        kw = {} if rtol is None else {"rtol": rtol}
        setting = "defaults" if rtol is None else f"rtol {rtol:.0e}"

        def run(kw: dict = kw) -> gp.Trajectory:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return gp.simulate(model, q0, v0, t_end, record=grid, throw=False, **kw)

        try:
            traj, wall, first = timed(run)
        except Exception as exc:  # a failure before any trajectory exists
            rows.append(progress(Row(problem, code, setting, status="failed", note=f"{type(exc).__name__}: {exc}")))
            continue
        row = Row(problem, code, setting, wall, first, status=traj.status, steps=int(traj.steps))
        if traj.status == "failed":
            at = float(traj.t[-1]) if len(traj.t) else 0.0
            row.note = f"stopped at t = {at:.3g}: {type(traj.failure).__name__}: {traj.failure}"[:200]
            if at <= 0.0:  # refused at the start: every setting is refused alike
                row.setting = "every setting"
                rows.append(progress(row))
                break
        else:
            row.error = error(traj)
        rows.append(progress(row))
    return rows


# -------------------------------------------------------------------------------------------------- MuJoCo


def mujoco_rows(
    mujoco: ModuleType,
    problem: str,
    code: str,
    xml: Callable[[float], str],
    start: Callable[[Any, Any], None],
    output: Callable[[Any, Any], np.ndarray],
    grid: np.ndarray,
    reference: np.ndarray,
    dts: list[float],
    angle: bool = False,
) -> list[Row]:
    """RK4 at each ``dt``: ``mj_step(model, data, n)`` between the record times, timed whole; the outputs from the
    recorded ``qpos`` by ``mj_kinematics`` afterwards."""
    rows = []
    for dt in dts:
        model = mujoco.MjModel.from_xml_string(xml(dt))
        data, probe = mujoco.MjData(model), mujoco.MjData(model)
        per = round((grid[1] - grid[0]) / dt)

        def run(model: Any = model, data: Any = data, per: int = per) -> list[np.ndarray]:
            mujoco.mj_resetData(model, data)
            start(model, data)
            out = [data.qpos.copy()]
            for _ in range(len(grid) - 1):
                mujoco.mj_step(model, data, per)
                out.append(data.qpos.copy())
            return out

        qpos, wall, first = timed(run)
        values = []
        for q in qpos:
            probe.qpos[:] = q
            mujoco.mj_kinematics(model, probe)
            values.append(output(model, probe))
        ok = bool(np.all(np.isfinite(qpos)))
        rows.append(
            progress(
                Row(
                    problem,
                    code,
                    f"RK4 dt {dt:g}",
                    wall,
                    first,
                    distance(np.array(values), reference, angle) if ok else math.nan,
                    "success" if ok else "failed",
                    steps=per * (len(grid) - 1),
                )
            )
        )
    return rows


def distance(values: np.ndarray, reference: np.ndarray, angle: bool = False) -> float:
    """The largest difference over the grid: absolute for an angle, Euclidean for a point."""
    reference = np.asarray(reference, float)
    diff = np.asarray(values, float).reshape(reference.shape) - reference
    if angle or diff.ndim == 1:
        return float(np.abs(diff).max())
    return float(np.linalg.norm(diff, axis=1).max())


def pendulum_mjcf(dt: float, hinge: bool) -> str:
    """A01 as MJCF (benchmarks/peers.py's): the body at ``(L, 0, 0)``, on a free joint pinned by a connect at its
    stiffest, or on a hinge at the pin; gravity ``−z``."""
    joint = '<joint type="hinge" axis="0 1 0" pos="-1 0 0"/>' if hinge else "<freejoint/>"
    equality = "" if hinge else f'<connect body1="b" anchor="-1 0 0" {mjp.stiffest(dt)}/>'
    return f"""
<mujoco>
  <option timestep="{dt}" integrator="RK4" gravity="0 0 {-G}"><flag contact="disable"/></option>
  <worldbody>
    <body name="b" pos="1 0 0">{joint}<inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>
  </worldbody>
  <equality>{equality}</equality>
</mujoco>"""


# -------------------------------------------------------------------------------------------------- Exudyn


def exudyn_module() -> ModuleType | None:
    """Exudyn, or ``None`` (said) when it is not installed: it is no extra of gausspp's (``pip install exudyn``)."""
    try:
        import exudyn
    except ImportError:
        print("exudyn is not installed (pip install exudyn): its rows are skipped")
        return None
    return exudyn


def exudyn_settings(exu: ModuleType, h: float, t_end: float, period: float, redundant: bool) -> Any:
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = round(t_end / h)
    s.timeIntegration.endTime = t_end
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = period
    s.show.computationTime = False
    s.show.statistics = False
    if redundant:  # Exudyn's recipe for redundant constraints (its solver's own hint)
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense
        s.linearSolver.ignoreSingularJacobian = True
    return s


def exudyn_rows(
    exu: ModuleType,
    problem: str,
    build: Callable[[], tuple[Any, Any, Any]],
    output: Callable[[np.ndarray], np.ndarray],
    grid: np.ndarray,
    reference: np.ndarray,
    hs: list[float],
    redundant: bool,
    angle: bool = False,
) -> list[Row]:
    """Generalized-α at each ``h``: ``SolveDynamic`` whole, warm; the sensor's samples at the record times."""
    rows = []
    _, mbs, sensor = build()
    t_end, period = float(grid[-1]), float(grid[1] - grid[0])
    for h in hs:
        settings = exudyn_settings(exu, h, t_end, period, redundant)

        def run(settings: Any = settings) -> tuple[bool, np.ndarray]:
            try:
                ok = mbs.SolveDynamic(settings)
            except Exception:  # Exudyn raises when Newton fails for good
                ok = False
            return bool(ok), np.array(mbs.GetSensorStoredData(sensor))

        (ok, data), wall, first = timed(run)
        row = Row(problem, "Exudyn", f"gen-α h {h:g}", wall, first, status="success" if ok else "failed")
        row.steps = round(t_end / h)
        if ok:
            at = [int(np.argmin(np.abs(data[:, 0] - t))) for t in grid]
            if np.abs(data[at, 0] - grid).max() > h / 2:
                row.status, row.note = "failed", "the sensor misses record times"
            else:
                row.error = distance(output(data[at, 1:]), reference, angle)
        rows.append(progress(row))
    return rows


def exudyn_planar(exu: ModuleType, bars: list[tuple], pins: list[tuple], sensor_at: tuple) -> tuple[Any, Any, Any]:
    """2-D rigid bodies ``(mass, Ic, (x, y, θ), (vx, vy, ω))`` and revolute 2-D joints ``(body or None, local,
    body, local)`` (``None``: the ground at ``local``); a position sensor on ``sensor_at = (body, local)``."""
    from exudyn.utilities import (
        MarkerBodyPosition,
        ObjectJointRevolute2D,
        RigidBodyInertia,
        RotationMatrixZ,
        SensorBody,
    )

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround()
    bodies = []
    for mass, ic, (x, y, th), (vx, vy, w) in bars:
        inertia = RigidBodyInertia(mass=mass, inertiaTensor=np.diag([ic, ic, ic]), inertiaTensorAtCOM=True)
        bodies.append(
            mbs.CreateRigidBody(
                inertia=inertia,
                referencePosition=[x, y, 0.0],
                referenceRotationMatrix=RotationMatrixZ(th),
                initialVelocity=[vx, vy, 0.0],
                initialAngularVelocity=[0.0, 0.0, w],
                gravity=[0.0, -G, 0.0],
                create2D=True,
            )
        )
    for a, pa, b, pb in pins:
        ma = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground if a is None else bodies[a], localPosition=[*pa, 0.0]))
        mb = mbs.AddMarker(MarkerBodyPosition(bodyNumber=bodies[b], localPosition=[*pb, 0.0]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[ma, mb]))
    body, local = sensor_at
    sensor = mbs.AddSensor(
        SensorBody(
            bodyNumber=bodies[body],
            localPosition=[*local, 0.0],
            storeInternal=True,
            writeToFile=False,
            outputVariableType=exu.OutputVariableType.Position,
        )
    )
    mbs.Assemble()
    return SC, mbs, sensor


def exudyn_bricard(exu: ModuleType) -> tuple[Any, Any, Any]:
    """A04 in Exudyn: five rigid bodies (Euler parameters) where ``bricard()`` puts them, six ``CreateRevoluteJoint``
    on the cube's corners and axes; a position sensor on P3 (rod 3's end)."""
    from exudyn.utilities import RigidBodyInertia, SensorBody

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround()
    corners, axes = example.BRICARD_CORNERS, example.BRICARD_AXES
    bodies = []
    for i in range(5):
        a, b = corners[i], corners[i + 1]
        ex = b - a  # body x along the rod, as bricard() builds it
        ez = np.cross(ex, axes[i] if abs(axes[i] @ ex) < 0.5 else [0, 0, 1.0])
        R = np.column_stack([ex, np.cross(ez, ex) / np.linalg.norm(ez), ez / np.linalg.norm(ez)])
        inertia = RigidBodyInertia(
            mass=1.0, inertiaTensor=np.diag([0.02 / 12, 1.01 / 12, 1.01 / 12]), inertiaTensorAtCOM=True
        )
        bodies.append(
            mbs.CreateRigidBody(
                inertia=inertia, referencePosition=(a + b) / 2, referenceRotationMatrix=R, gravity=[0.0, -G, 0.0]
            )
        )
    items = [ground, *bodies, ground]
    for i in range(6):
        mbs.CreateRevoluteJoint(itemNumbers=[items[i], items[i + 1]], position=corners[i], axis=axes[i])
    sensor = mbs.AddSensor(
        SensorBody(
            bodyNumber=bodies[2],
            localPosition=[0.5, 0.0, 0.0],
            storeInternal=True,
            writeToFile=False,
            outputVariableType=exu.OutputVariableType.Position,
        )
    )
    mbs.Assemble()
    return SC, mbs, sensor


# ------------------------------------------------------------------------------------------------ problems


def a01(t_end: float, grid: np.ndarray, cfg: argparse.Namespace) -> list[Row]:
    scene = pendulum.build(t_end=t_end)
    reference = np.array([scene.exact(t)[0][:2] for t in grid])
    rows = gausspp_rows(
        "A01",
        "gausspp",
        scene.model,
        scene.q0,
        scene.v0,
        t_end,
        grid,
        lambda traj: distance(traj.q[:, :2], reference),
        cfg.rtols,
    )
    if cfg.mujoco is not None:
        for code, hinge in (("MuJoCo", False), ("MuJoCo hinge", True)):
            rows += mujoco_rows(
                cfg.mujoco,
                "A01",
                code,
                lambda dt, h=hinge: pendulum_mjcf(dt, h),
                lambda m, d: None,
                lambda m, d: d.xpos[1][[0, 2]].copy(),
                grid,
                reference,
                cfg.dts,
            )
    if cfg.exudyn is not None:
        exu = cfg.exudyn
        rows += exudyn_rows(
            exu,
            "A01",
            lambda: exudyn_planar(
                exu, [(1.0, 0.01, (1.0, 0.0, 0.0), (0, 0, 0))], [(None, (0.0, 0.0), 0, (-1.0, 0.0))], (0, (0.0, 0.0))
            ),
            lambda xyz: xyz[:, :2],
            grid,
            reference,
            cfg.hs,
            redundant=False,
        )
    return rows


def a02(t_end: float, grid: np.ndarray, cfg: argparse.Namespace) -> list[Row]:
    theta, _ = P.one_dof_reference(grid)
    mb = example.four_bar()
    q0, v0 = mb.assemble(fix={"crank1.θ": np.pi / 2}, rates={"crank1.θ̇": -1.0})
    rows = gausspp_rows(
        "A02",
        "gausspp",
        mb.model(),
        q0,
        v0,
        t_end,
        grid,
        lambda traj: distance(traj.q[:, 2], theta, angle=True),
        cfg.rtols,
    )
    machine = gp.from_mjcf(mjp.ladder_mjcf(1))
    crank, coupler, crank2 = (
        machine.mujoco_model.joint(machine.mujoco_model.body(b).jntadr[0]).qposadr[0]
        for b in ("crank0", "coupler0", "crank1")
    )
    qj, vj = machine.initial_state()
    vj = np.array(vj, float)
    vj[[crank, coupler, crank2]] = -1.0, 1.0, -1.0  # the cranks clockwise, the coupler kept level
    rows += gausspp_rows(
        "A02",
        "gausspp from_mjcf",
        machine.model,
        qj,
        vj,
        t_end,
        grid,
        lambda traj: distance(np.pi / 2 + traj.q[:, crank], theta, angle=True),
        cfg.rtols,
    )
    if cfg.mujoco is not None:

        def start(m: Any, d: Any) -> None:
            d.qvel[[crank, coupler, crank2]] = -1.0, 1.0, -1.0

        rows += mujoco_rows(
            cfg.mujoco,
            "A02",
            "MuJoCo",
            lambda dt: mjp.ladder_mjcf(1, dt=dt),
            start,
            lambda m, d: np.pi / 2 + float(d.qpos[crank]),
            grid,
            theta,
            cfg.dts,
            angle=True,
        )
    if cfg.exudyn is not None:
        exu = cfg.exudyn
        q, v, _ = P.maximal_state(np.pi / 2, -1.0)
        bars = [(1.0, 1.0 / 12, tuple(q[3 * i : 3 * i + 3]), tuple(v[3 * i : 3 * i + 3])) for i in range(3)]
        pins = [
            (None, (0.0, 0.0), 0, (-0.5, 0.0)),
            (0, (0.5, 0.0), 1, (-0.5, 0.0)),
            (1, (0.5, 0.0), 2, (0.5, 0.0)),
            (None, (1.0, 0.0), 2, (-0.5, 0.0)),
        ]

        def crank_angle(xyz: np.ndarray) -> np.ndarray:
            return np.unwrap(np.arctan2(xyz[:, 1], xyz[:, 0]))

        rows += exudyn_rows(
            exu,
            "A02",
            lambda: exudyn_planar(exu, bars, pins, (0, (0.5, 0.0))),
            crank_angle,
            grid,
            theta,
            cfg.hs,
            redundant=True,
            angle=True,
        )
    return rows


def a03(cfg: argparse.Namespace) -> list[Row]:
    scene = andrews.build()
    ref = andrews.reference(scene, "converged")
    grid = np.array([0.0, ref.t])
    return gausspp_rows(
        "A03",
        "gausspp",
        scene.model,
        scene.q0,
        scene.v0,
        ref.t,
        grid,
        lambda traj: float(np.abs(traj.q[-1] - ref.q).max()),
        cfg.rtols,
    )


def p3_maximal(q: np.ndarray) -> np.ndarray:
    """P3 — rod 3's end ``(0.5, 0, 0)`` in its body frame — from ``gp.Multibody``'s maximal coordinates."""
    from scipy.spatial.transform import Rotation

    rod = np.atleast_2d(q)[:, 14:21]  # link3: centre, quaternion (w, x, y, z)
    return rod[:, :3] + Rotation.from_quat(rod[:, [4, 5, 6, 3]]).apply([0.5, 0.0, 0.0])


def a04(t_end: float, grid: np.ndarray, cfg: argparse.Namespace) -> list[Row]:
    mb = example.bricard()
    model = mb.model()
    q0, v0 = mb.assemble()
    machine = gp.from_mjcf(example.bricard_mjcf(1e-3))
    qj, vj = machine.initial_state()
    mjm = machine.mujoco_model
    mjd = None
    if cfg.mujoco is not None:
        mjd = cfg.mujoco.MjData(mjm)

    def p3_joint(qs: np.ndarray) -> np.ndarray:  # link4's frame is at P3 (bricard_mjcf: body frames at the corners)
        if cfg.mujoco is None:
            raise RuntimeError("MuJoCo is needed for the joint-coordinate outputs")
        out = []
        for q in qs:
            mjd.qpos[:] = q
            cfg.mujoco.mj_kinematics(mjm, mjd)
            out.append(mjd.xpos[4].copy())
        return np.array(out)

    tight = dict(rtol=1e-13, atol=1e-13, record=grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref_joint = p3_joint(gp.simulate(machine.model, qj, vj, t_end, **tight).q)
        ref_max = p3_maximal(gp.simulate(model, q0, v0, t_end, **tight).q)
    floor = FLOORS["A04"] = distance(ref_joint, ref_max)
    print(f"  A04 references: the two tight runs (maximal, joint coordinates) differ by {floor:.1e} m", flush=True)
    rows = gausspp_rows(
        "A04", "gausspp", model, q0, v0, t_end, grid, lambda traj: distance(p3_maximal(traj.q), ref_joint), cfg.rtols
    )
    rows += gausspp_rows(
        "A04",
        "gausspp from_mjcf",
        machine.model,
        qj,
        vj,
        t_end,
        grid,
        lambda traj: distance(p3_joint(traj.q), ref_max),
        cfg.rtols,
    )
    if cfg.mujoco is not None:
        rows += mujoco_rows(
            cfg.mujoco,
            "A04",
            "MuJoCo",
            example.bricard_mjcf,
            lambda m, d: None,
            lambda m, d: d.xpos[4].copy(),
            grid,
            ref_joint,
            cfg.dts,
        )
    if cfg.exudyn is not None:
        exu = cfg.exudyn
        rows += exudyn_rows(
            exu, "A04", lambda: exudyn_bricard(exu), lambda xyz: xyz, grid, ref_joint, cfg.hs, redundant=True
        )
    return rows


# ------------------------------------------------------------------------------------------------ reporting


def print_rows(rows: list[Row]) -> None:
    print(
        f"\n{'problem':7s} {'code':20s} {'setting':14s} {'wall ms':>10s} {'1st ms':>10s} {'steps':>7s} {'error':>9s}"
        "  status"
    )
    print("-" * 108)
    for r in rows:
        error = "" if math.isnan(r.error) else f"{r.error:9.1e}"
        wall = "" if math.isnan(r.wall_ms) else f"{r.wall_ms:10.1f}"
        first = "" if math.isnan(r.first_ms) else f"{r.first_ms:10.1f}"
        note = f"  ({r.note})" if r.note and r.status == "failed" else ""
        steps = f"{int(r.steps):7d}" if r.steps else ""
        head = f"{r.problem:7s} {r.code:20s} {r.setting:14s} {wall:>10s} {first:>10s} {steps:>7s} {error:>9s}"
        print(f"{head}  {r.status}{note}")


def fastest(rows: list[Row], level: float) -> Row | None:
    """The fastest row that reached ``T`` with an error at most ``level``."""
    done = [r for r in rows if r.status in ("success", "drifted") and r.error <= level]
    return min(done, key=lambda r: r.wall_ms) if done else None


def print_fastest(rows: list[Row]) -> None:
    print("\nThe fastest wall (ms) each code needs to reach an error (runs that reached T):")
    print(f"{'problem':7s} {'code':20s}" + "".join(f" {'≤ ' + f'{lv:.0e}':>28s}" for lv in LEVELS))
    for problem in dict.fromkeys(r.problem for r in rows):
        for code in dict.fromkeys(r.code for r in rows if r.problem == problem):
            mine = [r for r in rows if r.problem == problem and r.code == code]
            cells = []
            for level in LEVELS:
                best = fastest(mine, level)
                cells.append("not reached" if best is None else f"{best.wall_ms:.1f} ({best.setting})")
            print(f"{problem:7s} {code:20s}" + "".join(f" {c:>28s}" for c in cells))


STYLE = {
    "gausspp": ("C0", "o"),
    "gausspp from_mjcf": ("C9", "D"),
    "MuJoCo": ("C1", "s"),
    "MuJoCo hinge": ("C3", "v"),
    "Exudyn": ("C2", "^"),
}
TITLES = {
    "A01": "A01 pendulum",
    "A02": "A02 parallelogram four-bar",
    "A03": "A03 Andrews (0.03 s)",
    "A04": "A04 Bricard",
}


def draw(rows: list[Row], path: str, t_end: float) -> None:
    plt = headless_pyplot()
    if plt is None:
        return
    problems = list(dict.fromkeys(r.problem for r in rows))
    cols = 2
    fig, axes = plt.subplots(
        (len(problems) + 1) // cols,
        cols,
        figsize=(11, 4.2 * ((len(problems) + 1) // cols)),
        layout="constrained",
        squeeze=False,
    )
    for ax, problem in zip(axes.flat, problems, strict=False):
        for code in dict.fromkeys(r.code for r in rows if r.problem == problem):
            color, marker = STYLE.get(code, ("k", "x"))
            done = [r for r in rows if r.problem == problem and r.code == code and np.isfinite(r.error)]
            done = [r for r in done if r.status in ("success", "drifted")]
            if not done:  # every run failed: said in the legend, the reason in the table
                ax.plot([], [], "x", color=color, label=f"{code}: failed")
                continue
            curve = [r for r in done if r.setting != "defaults"]  # in the order of the settings: looser to tighter
            ax.plot([r.error for r in curve], [r.wall_ms / 1e3 for r in curve], "-", color=color, lw=1)
            for r in done:
                hollow = r.status == "drifted"
                ax.plot(
                    r.error,
                    r.wall_ms / 1e3,
                    marker,
                    color=color,
                    mfc="none" if hollow else color,
                    ms=9 if r.setting == "defaults" else 6,
                )
            ax.plot([], [], "-" + marker, color=color, label=code)
        if problem in FLOORS:
            ax.axvline(FLOORS[problem], color="0.5", ls=":", lw=1)
            ax.text(
                FLOORS[problem],
                0.02,
                " reference floor",
                rotation=90,
                va="bottom",
                fontsize=7,
                color="0.4",
                transform=ax.get_xaxis_transform(),
            )
        ax.set(
            xscale="log",
            yscale="log",
            xlabel="error against the reference",
            ylabel="wall time (s)",
            title=TITLES.get(problem, problem),
        )
        ax.invert_xaxis()
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(problems) :]:
        ax.set_visible(False)
    fig.suptitle(
        f"IFToMM problems over {t_end:g} s: wall time against error (large markers: gausspp's defaults; "
        'hollow: "drifted")',
        fontsize=10,
    )
    fig.savefig(path, dpi=110)
    print(f"figure: {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2 s and fewer settings (about a minute)")
    parser.add_argument("--figure", metavar="PATH", help="save the work-precision figure there")
    parser.add_argument("--problems", default="A01,A02,A03,A04", help="which problems (comma-separated)")
    cfg = parser.parse_args()
    t_end = 2.0 if cfg.quick else 10.0
    cfg.rtols = QUICK_RTOLS if cfg.quick else RTOLS
    cfg.dts = QUICK_DTS if cfg.quick else DTS
    cfg.hs = QUICK_HS if cfg.quick else HS
    cfg.mujoco = peer("mujoco")
    cfg.exudyn = exudyn_module()
    grid = np.linspace(0.0, t_end, round(t_end / 0.1) + 1)
    wanted = cfg.problems.split(",")
    print(f"IFToMM work-precision over {t_end:g} s (A03: 0.03 s); errors: the largest over t = 0, 0.1, …, T")
    rows: list[Row] = []
    if "A01" in wanted:
        rows += a01(t_end, grid, cfg)
    if "A02" in wanted:
        rows += a02(t_end, grid, cfg)
    if "A03" in wanted:
        rows += a03(cfg)
    if "A04" in wanted:
        rows += a04(t_end, grid, cfg)
    print("A05 (flyball governor): skipped — no independent reference of its motion (see the docstring)")
    print_rows(rows)
    print_fastest(rows)
    if cfg.figure:
        draw(rows, cfg.figure, t_end)


if __name__ == "__main__":
    main()
