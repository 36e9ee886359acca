"""gausspp beside MuJoCo and Pinocchio on one problem, in one run: ``python benchmarks/peers.py [--figure PATH]``.

The problem (P2 of issue 17): the pendulum held by a point constraint — one rigid body, mass
``m = 1``, central moment of inertia ``Ic = 0.01``, pinned at distance ``L = 1`` from its centre of
mass, released horizontal at rest under gravity ``g = 9.81``; ``T = 2 s``, ``dt = 1e-3`` (2000 steps).
gausspp has it as the ``pendulum`` scene, whose ``exact`` (the 1-DOF equation about the pin,
``(Ic + m L²) φ̈ = −m g L cos φ``, solved to ~1e-12) is the reference for every row.

Rows:

- **gausspp** — the whole ``gp.simulate`` call (set-up and recording included) with ``rk4`` in the Python
  and the compiled lanes, step solver ``direct`` and ``qp``; DOP853 at ``rtol = atol = 1e-10``; one checked
  ``model.step`` call.
- **MuJoCo** (optional) — the body on a free joint pinned by an ``equality connect``, integrator RK4,
  ``timestep = dt``, with the default equality softness and the stiffest one MuJoCo allows
  (``solref`` time constant ``2 dt``, ``solimp`` impedance 0.9999); then the same body on a hinge at
  the pin (no constraint at all: a reduced-coordinate pendulum, reported apart). Wall of 2000 ``mj_step``.
- **Pinocchio** (optional) — the body on a free-flyer joint, a ``RigidConstraintModel`` (3-D point
  contact) at the pin, ``constraintDynamics`` as the right-hand side of a classical RK4 written in
  Python on the Lie group (``pin.integrate``); one ``constraintDynamics`` call.

The 3-D peers move in the ``x``–``z`` plane (gravity ``−z``; the body's angle ``φ`` about the pin is
``atan2(R₂₀, R₀₀)`` of its rotation ``R``). The errors at ``T`` are, as for gausspp, the largest
absolute differences of ``(x, z, φ)`` (column ``error q``) and of ``(ẋ, ż, φ̇)`` (``error v``) from
the reference; the figure plots the larger of the two. (MuJoCo's soft equality errs more in velocity
than in position.)

Each time is the MINIMUM over ``--repeats`` of the mean time per call (``benchmarks/_timing.py``);
a missing peer (``pip install gausspp[peers]``: mujoco, pin) is said and its rows skipped.
The ratios printed last are those issue 17's acceptance names.
"""

from __future__ import annotations

import argparse
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np
from _figures import headless_pyplot
from _optional import peer
from _timing import best_us

import gausspp as gp

P2 = dict(m=1.0, Ic=0.01, L=1.0, g=9.81, phi0=0.0, omega0=0.0, t_end=2.0)
DT = 1e-3
STEPS = round(P2["t_end"] / DT)  # 2000


@dataclass
class Row:
    what: str
    wall_ms: float = math.nan  # the whole run
    per_step_us: float = math.nan  # wall / steps, or one call
    error_q: float = math.nan  # at T, max |q − q*| of (x, z, φ)
    error_v: float = math.nan  # at T, max |v − v*| of (ẋ, ż, φ̇)
    steps: int = STEPS

    @property
    def error(self) -> float:
        return max(self.error_q, self.error_v)


def state_error(scene: gp.scenes.Scene, t: float, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """``max |q − q*|`` and ``max |v − v*|`` at ``t`` for ``q = (x, z, φ)``, ``v = (ẋ, ż, φ̇)``."""
    q_ref, v_ref = scene.exact(t)
    return float(np.abs(q - q_ref).max()), float(np.abs(v - v_ref).max())


def planar_state(position: np.ndarray, rotation: np.ndarray, velocity: np.ndarray, omega: np.ndarray) -> tuple:
    """``(x, z, φ), (ẋ, ż, φ̇)`` of a body moving in the x–z plane, from world-frame quantities."""
    phi = math.atan2(rotation[2, 0], rotation[0, 0])
    return np.array([position[0], position[2], phi]), np.array([velocity[0], velocity[2], -omega[1]])


def timed_run(
    what: str, run: Callable[[], Any], error: Callable[[Any], tuple[float, float]], args: argparse.Namespace
) -> Row:
    """A row for a whole run: min-over-repeats wall, and the errors of one run's result."""
    wall_us = best_us(run, args.budget, args.repeats)
    return Row(what, wall_us / 1e3, wall_us / STEPS, *error(run()))


def call_row(what: str, call: Callable[[], Any], args: argparse.Namespace) -> Row:
    """A row for one call (µs)."""
    return Row(what, per_step_us=best_us(call, args.budget, args.repeats), steps=1)


# ----------------------------------------------------------------------------------------------- gausspp


def gausspp_rows(scene: gp.scenes.Scene, args: argparse.Namespace) -> list[Row]:
    """``gp.simulate`` (rk4 from Python and compiled × direct, qp; DOP853) and one checked ``model.step``."""
    model, q0, v0, t_end = scene.model, scene.q0, scene.v0, scene.t_end

    def error(traj: Any) -> tuple[float, float]:
        return state_error(scene, traj.t[-1], traj.q[-1], traj.v[-1])

    rows = []
    for lane in ("python", "compiled"):
        for solver in ("direct", "qp"):
            run = lambda ln=lane, s=solver: gp.simulate(model, q0, v0, t_end, dt=DT, method="rk4", lane=ln, solver=s)  # noqa: E731
            rows.append(timed_run(f"gausspp simulate rk4 {lane} {solver}", run, error, args))
    for solver in ("direct", "qp"):
        run = lambda s=solver: gp.simulate(model, q0, v0, t_end, method="DOP853", solver=s, rtol=1e-10, atol=1e-10)  # noqa: E731
        row = timed_run(f"gausspp simulate DOP853 {solver}", run, error, args)
        row.steps = run().steps
        row.per_step_us = row.wall_ms * 1e3 / row.steps
        rows.append(row)
    for label, kw in (("default", {}), ("default, direct", {"solver": "direct"})):
        run = lambda kw=kw: gp.simulate(model, q0, v0, t_end, **kw)  # noqa: E731
        row = timed_run(f"gausspp simulate {label} (no dt)", run, error, args)
        row.steps = run().steps
        row.per_step_us = row.wall_ms * 1e3 / row.steps
        rows.append(row)
    lam = np.zeros(model.n_lam)
    for solver in ("direct", "qp"):
        call = lambda s=solver: model.step(0.0, q0, v0, lam, solver=s)  # noqa: E731
        rows.append(call_row(f"gausspp model.step {solver} (one call)", call, args))
    return rows


# ------------------------------------------------------------------------------------------------ MuJoCo

STIFFEST = 'solref="0.002 1" solimp="0.9999 0.9999 0.001 0.5 2"'  # time constant 2·dt: refsafe's floor


def mjcf(joint: str, equality: str) -> str:
    """P2 as MJCF: the body at ``(L, 0, 0)``, its frame at the centre of mass."""
    p = P2
    return f"""
<mujoco>
  <option timestep="{DT}" integrator="RK4" gravity="0 0 {-p["g"]}"/>
  <worldbody>
    <body name="b" pos="{p["L"]} 0 0">
      {joint}
      <inertial pos="0 0 0" mass="{p["m"]}" diaginertia="{p["Ic"]} {p["Ic"]} {p["Ic"]}"/>
    </body>
  </worldbody>
  <equality>{equality}</equality>
</mujoco>"""


def mujoco_models(mujoco: ModuleType) -> list[tuple[str, Any]]:
    pin = f'<connect body1="b" anchor="{-P2["L"]} 0 0"'
    variants = [
        ("MuJoCo RK4 connect, default", mjcf('<freejoint name="f"/>', pin + "/>")),
        ("MuJoCo RK4 connect, stiffest", mjcf('<freejoint name="f"/>', f"{pin} {STIFFEST}/>")),
        ("MuJoCo RK4 hinge (no constraint)", mjcf(f'<joint type="hinge" axis="0 1 0" pos="{-P2["L"]} 0 0"/>', "")),
    ]
    return [(what, mujoco.MjModel.from_xml_string(xml)) for what, xml in variants]


def mujoco_rows(mujoco: ModuleType, scene: gp.scenes.Scene, args: argparse.Namespace) -> list[Row]:
    """2000 ``mj_step`` from the initial state, for each variant of :func:`mujoco_models`."""
    rows = []
    for what, model in mujoco_models(mujoco):
        data = mujoco.MjData(model)
        body = model.body("b").id

        def run(model: Any = model, data: Any = data) -> Any:
            mujoco.mj_resetData(model, data)
            for _ in range(STEPS):
                mujoco.mj_step(model, data)
            return data

        def error(data: Any, model: Any = model, body: int = body) -> tuple[float, float]:
            mujoco.mj_forward(model, data)  # positions and velocities at T (mj_step leaves them at T − dt)
            twist = np.zeros(6)  # (ω, v), world orientation, at the body's frame origin = centre of mass
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, body, twist, 0)
            q, v = planar_state(data.xpos[body], data.xmat[body].reshape(3, 3), twist[3:], twist[:3])
            return state_error(scene, data.time, q, v)

        rows.append(timed_run(what, run, error, args))
    return rows


# --------------------------------------------------------------------------------------------- Pinocchio


def pinocchio_problem(pin: ModuleType) -> tuple[Any, Any, Any, Any]:
    """The body on a free flyer at ``(L, 0, 0)`` and the 3-D point constraint pinning ``(−L, 0, 0)``."""
    p = P2
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "body")
    model.appendBodyToJoint(joint, pin.Inertia(p["m"], np.zeros(3), p["Ic"] * np.eye(3)), pin.SE3.Identity())
    model.gravity.linear = np.array([0.0, 0.0, -p["g"]])
    anchor = pin.SE3(np.eye(3), np.array([-p["L"], 0.0, 0.0]))
    constraint = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, joint, anchor, 0, pin.SE3.Identity())
    models = pin.StdVec_RigidConstraintModel()
    models.append(constraint)
    datas = pin.StdVec_RigidConstraintData()
    datas.append(constraint.createData())
    data = model.createData()
    pin.initConstraintDynamics(model, data, models, datas)
    return model, data, models, datas


def pinocchio_rows(pin: ModuleType, scene: gp.scenes.Scene, args: argparse.Namespace) -> list[Row]:
    """Classical RK4 in Python on ``constraintDynamics``; and one ``constraintDynamics`` call."""
    model, data, models, datas = pinocchio_problem(pin)
    q0 = pin.neutral(model)
    q0[0] = P2["L"]
    v0, tau = np.zeros(model.nv), np.zeros(model.nv)
    prox = pin.ProximalSettings(1e-12, 0.0, 1)  # mu = 0: the exact KKT solve (3 independent rows, no regularization)

    def accel(q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return pin.constraintDynamics(model, data, q, v, tau, models, datas, prox).copy()

    def run() -> tuple[np.ndarray, np.ndarray]:
        q, v, h = q0, v0, DT
        for _ in range(STEPS):
            k1v, k1a = v, accel(q, v)
            q2, v2 = pin.integrate(model, q, 0.5 * h * k1v), v + 0.5 * h * k1a
            k2v, k2a = v2, accel(q2, v2)
            q3, v3 = pin.integrate(model, q, 0.5 * h * k2v), v + 0.5 * h * k2a
            k3v, k3a = v3, accel(q3, v3)
            q4, v4 = pin.integrate(model, q, h * k3v), v + h * k3a
            k4a = accel(q4, v4)
            q = pin.integrate(model, q, h / 6 * (k1v + 2 * k2v + 2 * k3v + v4))
            v = v + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
        return q, v

    def error(state: tuple[np.ndarray, np.ndarray]) -> tuple[float, float]:
        q, v = state
        placement = pin.XYZQUATToSE3(q)
        rotation = placement.rotation  # free-flyer velocities are in the body frame
        return state_error(scene, P2["t_end"], *planar_state(q[:3], rotation, rotation @ v[:3], rotation @ v[3:]))

    rows = [timed_run("Pinocchio constraintDynamics + RK4 (Python)", run, error, args)]
    rows.append(call_row("Pinocchio constraintDynamics (one call)", lambda: accel(q0, v0), args))
    return rows


# ---------------------------------------------------------------------------------------------- reporting


def print_table(rows: list[Row]) -> None:
    print(f"\n{'what':48s} {'wall ms':>9s} {'µs/step':>9s} {'steps':>6s} {'error q':>9s} {'error v':>9s}")
    print("-" * 95)
    for r in rows:
        wall = "" if math.isnan(r.wall_ms) else f"{r.wall_ms:9.2f}"
        eq, ev = ("", "") if math.isnan(r.error) else (f"{r.error_q:9.1e}", f"{r.error_v:9.1e}")
        print(f"{r.what:48s} {wall:>9s} {r.per_step_us:9.2f} {r.steps:6d} {eq:>9s} {ev:>9s}")


def print_ratios(rows: list[Row]) -> None:
    """The ratios of issue 17's acceptance (targets: ≤ 0.5, ≤ 1.0, ≤ 3) and issue 30's (the default call, ≤ 0.2)."""
    by = {r.what: r for r in rows}
    mj = by.get("MuJoCo RK4 connect, stiffest")
    pc = by.get("Pinocchio constraintDynamics (one call)")
    print("\nratios (issues 17 and 30):")
    for label, num, den, target in (
        ("gp.simulate rk4 direct / MuJoCo RK4 (stiffest) wall", "gausspp simulate rk4 direct", mj, 0.5),
        ("gp.simulate rk4 qp     / MuJoCo RK4 (stiffest) wall", "gausspp simulate rk4 qp", mj, 1.0),
        ("gp.simulate default (no dt) / MuJoCo RK4 (stiffest) wall", "gausspp simulate default (no dt)", mj, 0.2),
        ("gp.simulate default, direct / MuJoCo RK4 wall", "gausspp simulate default, direct (no dt)", mj, 0.2),
        ("model.step direct / one Pinocchio constraintDynamics", "gausspp model.step direct (one call)", pc, 3.0),
        ("model.step qp     / one Pinocchio constraintDynamics", "gausspp model.step qp (one call)", pc, 3.0),
    ):
        if den is None:
            print(f"  {label}: peer not run")
            continue
        field = "per_step_us" if den is pc else "wall_ms"
        ratio = getattr(by[num], field) / getattr(den, field)
        met = ratio <= target
        accuracy = ""
        if "default" in num:  # issue 30: the default call at an error ≤ 1e-10
            error = max(by[num].error_q, by[num].error_v)
            met = met and error <= 1e-10
            accuracy = f" at error {error:.1e} (≤ 1e-10)"
        print(f"  {label}: {ratio:6.2f}{accuracy}   target ≤ {target:g}: {'met' if met else 'NOT met'}")


def print_agreement(scene: gp.scenes.Scene) -> None:
    """The compiled DOP853 stages (gausspp.simulation.compiled_adaptive) against scipy's own DOP853 with the same
    right-hand side and tolerances: the states at 21 record times, relative to the state's size (issue 30: ≤ 1e-12)."""
    import scipy.integrate as si

    from gausspp.simulation import compiled_adaptive
    from gausspp.simulation.drift import Stabilization
    from gausspp.simulation.initial import initial_state
    from gausspp.simulation.rhs import RightHandSide, step_control_atol

    m = scene.model
    q, v, lam = initial_state(m, 0.0, scene.q0, scene.v0, None)
    y0 = np.concatenate([q, v, lam, [0.0, 0.0]])
    times = np.linspace(0.0, scene.t_end, 21)[1:]
    for solver in ("direct", "qp"):
        rhs = RightHandSide(m, solver, None, Stabilization())
        out = []
        for cls in (si.DOP853, compiled_adaptive.solver_class("DOP853", rhs)):
            # the default call's tolerances (rtol = atol = 1e-10), the work integrals left out of the step control
            # as gp.simulate leaves them. (With atol = 1e-12 the first steps from rest are chosen by the round-off
            # of components that start at zero, where the two routes' round-off differs: 2e-11 apart for the QP.)
            atol = step_control_atol(1e-10, y0.size)
            run = si.solve_ivp(rhs, (0.0, scene.t_end), y0, method=cls, t_eval=times, rtol=1e-10, atol=atol)
            out.append(run.y.T)
        diff = float(np.abs(out[0] - out[1]).max() / (1.0 + np.abs(out[0]).max()))
        print(f"\ncompiled DOP853 vs scipy's DOP853 ({solver}, rtol = atol = 1e-10): {diff:.1e} relative (≤ 1e-12)")


def figure(rows: list[Row], path: str) -> None:
    """Error at T against wall time, one point per run (matplotlib, optional)."""
    plt = headless_pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 5))
    for r in rows:
        if not (math.isnan(r.wall_ms) or math.isnan(r.error)):
            marker = "o" if r.what.startswith("gausspp") else ("s" if r.what.startswith("MuJoCo") else "^")
            ax.loglog(r.wall_ms, max(r.error, 1e-16), marker, label=r.what)
    ax.set(xlabel="wall time of the whole run [ms]", ylabel="error at T", title=f"P2 pendulum, T = 2 s, dt = {DT:g}")
    ax.xaxis.set_minor_formatter(plt.NullFormatter())  # decade labels only
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"figure written to {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--budget", type=float, default=0.3, help="seconds per repeat of one row")
    parser.add_argument("--figure", metavar="PATH", help="error against wall time (needs matplotlib)")
    args = parser.parse_args()
    scene = gp.scenes.get("pendulum", **P2)
    mujoco, pin = peer("mujoco"), peer("pinocchio")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = gausspp_rows(scene, args)
    if mujoco is not None:
        rows += mujoco_rows(mujoco, scene, args)
    if pin is not None:
        rows += pinocchio_rows(pin, scene, args)
    versions = ", ".join(f"{m.__name__} {m.__version__}" for m in (gp, mujoco, pin) if m is not None)
    print(f"P2 pendulum, T = {P2['t_end']:g} s, dt = {DT:g} ({STEPS} steps); {versions}")
    print_table(rows)
    print_ratios(rows)
    print_agreement(scene)
    if args.figure:
        figure(rows, args.figure)


if __name__ == "__main__":
    main()
