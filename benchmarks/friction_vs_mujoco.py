"""Coulomb friction, gausspp beside MuJoCo, in one run: ``.venv/bin/python benchmarks/friction_vs_mujoco.py [--quick]``.

Two motions with closed forms (``g = 9.81``):

1. **A box sliding to rest** — released at ``v0 = 3`` m/s on a floor with ``μ = 0.4``, it decelerates at ``μg``
   and stops at ``t = v0/(μg) = 0.76453`` s after ``v0²/(2μg) = 1.14679`` m. gausspp: ``friction.scenes.box``
   (planar, ``0.4 × 0.2``, ``m = 1``, on its two bottom corners), ``gp.simulate_friction`` to 1 s; the stop is
   its ``'stops slipping'`` event; the wall is the whole call (set-up included, best of a few); its steps are
   the samples it records by default, one per DOP853 step (``len(run.t)``). MuJoCo: a box geom (half-extents
   ``0.2 0.1 0.1``, mass 1) on a free joint on a plane, elliptic cones, ``condim`` 3, friction
   ``0.4 0.005 0.0001`` on both geoms (MuJoCo takes the max); settled at rest for 0.2 s (four contacts), given
   ``ẋ = v0``, stepped until the horizontal speed is below 1e-3 m/s (or 2 s). Columns: the stop time and
   distance; the deceleration (least-squares slope of ``ẋ`` over 0.1–0.6 s); the mean number of contacts
   while sliding and the largest lift off the resting height (a soft, convex contact model can push a
   sliding body off the floor); the wall of the same physical 1 s (``mj_step(model, data, n)`` from the
   released state); µs per ``mj_step`` sliding (its first 0.5 s) and resting (zero velocity, four contacts).
2. **A ball thrown without spin** — ``v0 = 2`` m/s, ``μ = 0.3``, ``r = 0.1``: it slides, then rolls from
   ``t = 2v0/(7μg)`` at ``5v0/7``. gausspp: ``friction.scenes.round_body(0.3, 0.4, r=0.1)``, its first
   ``'stops slipping'`` event. MuJoCo: a sphere geom (radius 0.1, mass 1: solid-sphere inertia), friction
   ``0.3 0 0``; the first time the contact point's slip ``ẋ − r ω_y`` (world ``ω``) is below 1e-3 m/s.

MuJoCo's settings (label ``dt``, ``ref``, ``imp``): ``timestep`` 1e-3 and 1e-4; ``solref`` time constant 0.02
(its default), 0.002 or ``2 dt`` (the floor it allows), damping ratio 1; ``impratio`` 1 and 10; one row with
``noslip_iterations``. Its friction is soft, so a stop found by a speed threshold includes a slow
exponential tail. Each MuJoCo time is the minimum over repeats of the mean per call (``benchmarks/_timing.py``);
a missing mujoco (``pip install gausspp[peers]``) is said and its rows skipped.

Section 3, the cost per step: the box on its four corners (``scenes.spatial_box``, MuJoCo's box) in gausspp's
fixed steps of 1 ms (``simulate_friction(step=1e-3)``: compiled RK4 phases, events located inside their steps),
in casadi's virtual machine and as C (``codegen=True``), against ``mj_step`` at ``timestep`` 1e-3, both timed the
same way over the same windows (0.5 s sliding, 0.5 s resting, whole calls). The adaptive lane's per-step figure
is given beside them: few long steps from Python, not comparable one to one.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np
from _optional import peer
from _timing import best_ms, best_us

import gausspp as gp
from gausspp.friction import scenes

G = scenes.G
V_BOX, MU_BOX, V_BALL, MU_BALL, R = 3.0, 0.4, 2.0, 0.3, 0.1
T_STOP, D_STOP = V_BOX / (MU_BOX * G), V_BOX**2 / (2 * MU_BOX * G)
T_ROLL, V_ROLL = 2 * V_BALL / (7 * MU_BALL * G), 5 * V_BALL / 7
SLOW, SETTLE, HORIZON = 1e-3, 0.2, 2.0  # m/s; s at rest before the release; s at most after it
STEP = 1e-3  # gausspp's fixed step for the box on four corners: MuJoCo's default timestep

# timestep, solref time constant (0.02: MuJoCo's default; damping ratio 1), impratio, noslip_iterations
SETTINGS = [(1e-3, 0.02, 1, 0), (1e-3, 0.02, 10, 0), (1e-3, 0.02, 1, 10), (1e-3, 0.002, 10, 0)]
SETTINGS += [(1e-4, 0.02, 1, 0), (1e-4, 0.002, 10, 0), (1e-4, 0.0002, 10, 0)]
BOX_GEOM, BOX_FRICTION = '<geom type="box" size="0.2 0.1 0.1" mass="1" friction="{f}"/>', "0.4 0.005 0.0001"
BALL_GEOM, BALL_FRICTION = f'<geom type="sphere" size="{R}" mass="1" friction="{{f}}"/>', "0.3 0 0"


@dataclass
class Row:
    what: str
    t: float  # stop (box) or start of rolling (ball), s
    x: float  # distance (box), m, or rolling speed (ball), m/s
    lift: float  # largest height above the resting one, m
    decel: float = math.nan  # box: mean deceleration over 0.1–0.6 s, m/s²
    contacts: float = math.nan  # box: mean number of contacts while sliding
    wall_ms: float = math.nan  # the same physical 1 s
    steps: int = 0
    slide_us: float = math.nan  # per step, sliding (gausspp: per recorded sample)
    rest_us: float = math.nan  # per step, resting


# ----------------------------------------------------------------------------------------------- gausspp


def gausspp_box(repeats: int) -> Row:
    mech, contacts = scenes.box(MU_BOX)
    call = lambda **kw: gp.simulate_friction(mech, contacts, [0.0, 0.1, 0.0], [V_BOX, 0.0, 0.0], 1.0, **kw)  # noqa: E731
    wall, steps = best_ms(call, repeats), len(call().t)  # the timed call records the integrator's own steps
    run = call(record=np.linspace(0.0, 1.0, 1001))  # every ms, for the deceleration
    t = next(ev["t"] for ev in run.events if ev["kind"] == "stops slipping")
    row = Row("gausspp simulate_friction (DOP853)", t, float(np.interp(t, run.t, run.q[:, 0])), run.q[:, 1].max() - 0.1)
    row.decel, row.contacts = deceleration(run.t, run.v[:, 0]), len(contacts)
    row.wall_ms, row.steps, row.slide_us = wall, steps, wall * 1e3 / steps
    return row


def gausspp_box_on_four_corners(codegen: bool, args: argparse.Namespace) -> Row:
    """The spatial box on its four corners (``scenes.spatial_box``, MuJoCo's box), compiled RK4 steps of 1 ms."""
    mech, contacts = scenes.spatial_box(MU_BOX)
    q0, rest = [0.0, 0.0, 0.1, 1.0, 0.0, 0.0, 0.0], [0.0] * 6
    slide = [V_BOX, 0.0, 0.0, 0.0, 0.0, 0.0]

    def call(v0: list, t_end: float) -> Any:
        return gp.simulate_friction(mech, contacts, q0, v0, t_end, step=STEP, codegen=codegen)

    run = call(slide, 1.0)
    t = next(ev["t"] for ev in run.events if ev["kind"] == "stops slipping")
    what = f"gausspp RK4 h={STEP:g}, 4 corners, " + ("C" if codegen else "casadi VM")
    row = Row(what, t, float(np.interp(t, run.t, run.q[:, 0])), run.q[:, 2].max() - 0.1)
    row.decel, row.contacts, row.steps = deceleration(run.t, run.v[:, 0]), len(contacts), round(1.0 / STEP)
    row.wall_ms = best_us(lambda: call(slide, 1.0), args.budget, args.repeats) / 1e3
    half = round(0.5 / STEP)  # the same windows and timing as mj_step's: 0.5 s sliding, 0.5 s resting, whole calls
    row.slide_us = best_us(lambda: call(slide, 0.5), args.budget, args.repeats) / half
    row.rest_us = best_us(lambda: call(rest, 0.5), args.budget, args.repeats) / half
    return row


def deceleration(t: np.ndarray, vx: np.ndarray) -> float:
    """The deceleration over 0.1–0.6 s (sliding throughout): the least-squares slope of ``ẋ``."""
    window = (t >= 0.1) & (t <= 0.6)
    return -float(np.polyfit(t[window], vx[window], 1)[0])


def gausspp_ball() -> Row:
    mech, contacts = scenes.round_body(MU_BALL, 0.4, r=R)
    run = gp.simulate_friction(mech, contacts, [0.0, R, 0.0], [V_BALL, 0.0, 0.0], 1.0)
    t = next(ev["t"] for ev in run.events if ev["kind"] == "stops slipping")
    return Row("gausspp simulate_friction (DOP853)", t, float(np.interp(t, run.t, run.v[:, 0])), run.q[:, 1].max() - R)


# ------------------------------------------------------------------------------------------------ MuJoCo


def label(setting: tuple) -> str:
    dt, ref, imp, noslip = setting
    return f"MuJoCo dt={dt:g} ref={ref:g} imp={imp}" + (f" noslip={noslip}" if noslip else "")


def mjcf(setting: tuple, geom: str, friction: str) -> str:
    dt, ref, impratio, noslip = setting
    return f"""
<mujoco>
  <option timestep="{dt}" gravity="0 0 {-G}" cone="elliptic" impratio="{impratio}" noslip_iterations="{noslip}"/>
  <default><geom condim="3" solref="{ref:g} 1"/></default>
  <worldbody>
    <geom type="plane" size="5 5 0.1" friction="{friction}"/>
    <body pos="0 0 0.1"><freejoint/>{geom.format(f=friction)}</body>
  </worldbody>
</mujoco>"""


def snapshot(data: Any) -> tuple:
    return data.qpos.copy(), data.qvel.copy(), data.qacc_warmstart.copy(), data.time


def restore(data: Any, snap: tuple) -> None:
    data.qpos[:], data.qvel[:], data.qacc_warmstart[:], data.time = snap


def settled(mujoco: ModuleType, setting: tuple, geom: str, friction: str) -> tuple[Any, Any, tuple]:
    """Model and data after ``SETTLE`` s at rest (velocity zeroed, clock at 0), and that resting state."""
    model = mujoco.MjModel.from_xml_string(mjcf(setting, geom, friction))
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, round(SETTLE / model.opt.timestep))
    data.qvel[:], data.time = 0.0, 0.0
    return model, data, snapshot(data)


def mujoco_box(mujoco: ModuleType, setting: tuple, args: argparse.Namespace) -> tuple[Row, int]:
    model, data, rest = settled(mujoco, setting, BOX_GEOM, BOX_FRICTION)
    mujoco.mj_forward(model, data)
    ncon, x0, z0 = data.ncon, data.qpos[0], data.qpos[2]
    data.qvel[0] = V_BOX
    start, lift, t, times, vx, cons = snapshot(data), 0.0, math.nan, [0.0], [V_BOX], []
    while data.time < HORIZON:
        mujoco.mj_step(model, data)
        lift = max(lift, data.qpos[2] - z0)
        times.append(data.time), vx.append(data.qvel[0]), cons.append(data.ncon)  # ncon: at the step's start
        if math.hypot(data.qvel[0], data.qvel[1]) < SLOW:
            t = data.time
            break
    row = Row(label(setting), t, data.qpos[0] - x0, lift, deceleration(np.array(times), np.array(vx)))
    row.contacts = float(np.mean(cons))

    def steps(snap: tuple, n: int) -> None:
        restore(data, snap)
        mujoco.mj_step(model, data, n)

    row.steps, half = round(1.0 / model.opt.timestep), round(0.5 / model.opt.timestep)
    row.wall_ms = best_us(lambda: steps(start, row.steps), args.budget, args.repeats) / 1e3
    row.slide_us = best_us(lambda: steps(start, half), args.budget, args.repeats) / half
    row.rest_us = best_us(lambda: steps(rest, half), args.budget, args.repeats) / half
    return row, ncon


def mujoco_ball(mujoco: ModuleType, setting: tuple) -> Row:
    model, data, _ = settled(mujoco, setting, BALL_GEOM, BALL_FRICTION)
    z0, omega = data.qpos[2], np.zeros(3)
    data.qvel[0] = V_BALL
    lift = 0.0
    while data.time < HORIZON:
        mujoco.mj_step(model, data)
        lift = max(lift, data.qpos[2] - z0)
        mujoco.mju_rotVecQuat(omega, data.qvel[3:6], data.qpos[3:7])  # a free joint's ω is in the body frame
        if abs(data.qvel[0] - R * omega[1]) < SLOW:  # rolling along +x: ω_y > 0, ẋ = r ω_y
            return Row(label(setting), data.time, data.qvel[0], lift)
    return Row(label(setting), math.nan, data.qvel[0], lift)


# ---------------------------------------------------------------------------------------------- reporting


def fmt(value: float, spec: str, width: int) -> str:
    return " " * width if math.isnan(value) else format(value, f"{width}{spec}")


def print_box(rows: list[Row]) -> None:
    print(f"\n1. box sliding to rest: v0 = {V_BOX} m/s, μ = {MU_BOX}; closed form t = {T_STOP:.5f} s, ", end="")
    print(f"d = {D_STOP:.5f} m, deceleration μg = {MU_BOX * G:.3f} m/s²")
    head = (
        "t stop s  rel err   dist m  rel err decel err contacts lift mm wall 1 s ms  steps µs/step slide µs/step rest"
    )
    print(f"{'what':42s} {head}\n" + "-" * 148)
    for r in rows:
        t = "  > 2 s " if math.isnan(r.t) else f"{r.t:8.5f}"
        print(
            f"{r.what:42s} {t} {fmt(r.t / T_STOP - 1, '.1e', 8)} {r.x:8.5f} {r.x / D_STOP - 1:8.1e}"
            f" {r.decel / (MU_BOX * G) - 1:9.1e} {r.contacts:8.2f} {r.lift * 1e3:7.3f} {r.wall_ms:11.2f} {r.steps:6d}"
            f" {r.slide_us:13.2f} {fmt(r.rest_us, '.2f', 12)}"
        )


def print_ball(rows: list[Row]) -> None:
    print(f"\n2. ball thrown without spin: v0 = {V_BALL} m/s, μ = {MU_BALL}, r = {R}; closed form rolls from")
    print(f"   t = 2v0/(7μg) = {T_ROLL:.5f} s at 5v0/7 = {V_ROLL:.5f} m/s")
    print(f"{'what':42s} {'t roll s':>8s} {'rel err':>8s} {'speed':>8s} {'rel err':>8s} {'lift mm':>8s}\n" + "-" * 87)
    for r in rows:
        t = "  > 2 s " if math.isnan(r.t) else f"{r.t:8.5f}"
        print(
            f"{r.what:42s} {t} {fmt(r.t / T_ROLL - 1, '.1e', 8)} {r.x:8.5f} {r.x / V_ROLL - 1:8.1e} {r.lift * 1e3:8.3f}"
        )


def print_cost(g: Row, fixed: list[Row], mj_rows: list[Row]) -> None:
    print("\n3. cost per step: the box on its four corners, 1 ms steps on both sides, whole calls of 0.5 s sliding and")
    print("   0.5 s resting (gausspp: simulate_friction(step=1e-3), set-up, events and recording included; MuJoCo:")
    print("   mj_step(model, data, 500) from the released and from the resting state)")
    ref = next((r for r in mj_rows if r.what == label(SETTINGS[0])), None)
    for r in fixed:
        line = f"   {r.what:38s} {r.slide_us:7.2f} µs/step sliding, {r.rest_us:7.2f} resting"
        if ref is not None:
            ratio = max(r.slide_us / ref.slide_us, r.rest_us / ref.rest_us)
            line += f"; ×{r.slide_us / ref.slide_us:.2f} / ×{r.rest_us / ref.rest_us:.2f} mj_step"
            line += f" — ≤ 3×: {'met' if ratio <= 3 else 'not met'}"
        print(line)
    if ref is not None:
        print(f"   {ref.what:38s} {ref.slide_us:7.2f} µs/step sliding, {ref.rest_us:7.2f} resting")
    print(
        f"   gausspp adaptive (DOP853, planar box): 1 s in {g.wall_ms:.2f} ms, {g.steps} steps, {g.slide_us:.0f} µs per"
    )
    print("   step: few long steps, each a Python round trip, exact at every step.")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shorter timings (2 repeats, 0.05 s budget)")
    args = parser.parse_args()
    args.repeats, args.budget = (2, 0.05) if args.quick else (5, 0.3)
    mujoco = peer("mujoco")
    fixed = [gausspp_box_on_four_corners(codegen, args) for codegen in (False, True)]
    box, ball = [gausspp_box(args.repeats), *fixed], [gausspp_ball()]
    versions = f"gausspp {gp.__version__}" + (f", mujoco {mujoco.__version__}" if mujoco else "")
    if mujoco is not None:
        for setting in SETTINGS:
            row, ncon = mujoco_box(mujoco, setting, args)
            box.append(row)
            ball.append(mujoco_ball(mujoco, setting))
        versions += f"; MuJoCo's resting box has {ncon} contacts, elliptic cones, condim 3"
    print(versions)
    print_box(box)
    print_ball(ball)
    print_cost(box[0], fixed, box[len(fixed) + 1 :])


if __name__ == "__main__":
    main()
