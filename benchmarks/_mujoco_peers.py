"""MuJoCo beside the general-QP scenes: three planar problems built from MJCF strings and timed (``general_qp.py``).

Each function builds its MuJoCo model from an MJCF string, runs it from the scene's initial state, checks the
run (finite state, a constraint violation at the end reported as a number) and returns plain numbers in a
``dict``. The models move in a plane with hinge and slide joints only (MuJoCo's natural reduced coordinates
for a planar mechanism); a closed loop is cut at one joint and closed again by an ``<equality><connect>``
between two sites, with the stiffest softness MuJoCo allows (:func:`stiffest`, as ``benchmarks/peers.py``).

* :func:`four_bar` — gausspp's ``four-bar-redundant`` geometry: crank, coupler and rocker in a hinge chain
  whose joint angles are the scene's relative angles ``q = (θ1, θ2, θ3)``; one connect closes the loop at
  the rocker's ground pivot ``P``. In the x–y plane, gravity ``−y``, as the scene.
* :func:`box_drop` — gausspp's ``block-on-floor``: the block on slide x, slide z, hinge y (its joint values
  are the scene's ``(x, z, θ)``) above a plane, frictionless contacts whose soft spring–damper is set for the
  scene's restitution. In the x–z plane, gravity ``−z`` (MuJoCo's floor is the plane ``z = 0``).
* :func:`parallelogram_ladder` — ``N`` parallelogram cells side by side: ``N + 1`` cranks on ground hinges at
  ``x = 0, 1, …, N``, ``N`` couplers each hinged on crank ``i``'s tip and connected to crank ``i + 1``'s tip.
  In the x–y plane, gravity ``−y``.

Integrator RK4 everywhere; ``dt = 1e-3``. The timed run is MuJoCo's own loop (``mj_step(model, data, nstep)``,
no Python per step) from a reset and the initial state; each time is the minimum over repeats of the mean
(``benchmarks/_timing.py``). The state at the end is read after ``mj_forward`` (``mj_step`` leaves positions,
site positions and contacts at ``t − dt``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from _timing import best_us

from gausspp.scenes import four_bar as _four_bar

DT = 1e-3


def stiffest(dt: float = DT) -> str:
    """The stiffest equality softness MuJoCo allows: ``solref`` time constant ``2 dt`` (refsafe's floor), impedance
    0.9999 (``benchmarks/peers.py``'s ``STIFFEST`` at ``dt = 1e-3``)."""
    return f'solref="{2 * dt:g} 1" solimp="0.9999 0.9999 0.001 0.5 2"'


def _mujoco() -> Any:
    import mujoco  # the peers extra; the caller checks that it imports

    return mujoco


def _bar_inertial(length: float, mass: float, along: str) -> str:
    """A uniform thin bar from the body origin along ``+x`` or ``+y``: mass, centre, ``m l²/12`` about the normals."""
    moment = mass * length**2 / 12.0
    thin = moment * 1e-3  # about the bar's own axis (never turned about in the plane)
    if along == "x":
        return f'<inertial pos="{length / 2} 0 0" mass="{mass}" diaginertia="{thin} {moment} {moment}"/>'
    return f'<inertial pos="0 {length / 2} 0" mass="{mass}" diaginertia="{moment} {thin} {moment}"/>'


def _timed(mujoco: Any, model: Any, data: Any, start: Any, steps: int, budget: float, repeats: int) -> float:
    """µs of ``steps`` steps from ``start(data)`` (after a reset): min over repeats of the mean per run."""

    def run() -> None:
        mujoco.mj_resetData(model, data)
        start(data)
        mujoco.mj_step(model, data, steps)

    return best_us(run, budget, repeats)


def _finished(mujoco: Any, model: Any, data: Any, start: Any, steps: int, what: str) -> None:
    """One untimed run to the end, positions brought to ``t`` (``mj_forward``); a non-finite state raises."""
    mujoco.mj_resetData(model, data)
    start(data)
    mujoco.mj_step(model, data, steps)
    mujoco.mj_forward(model, data)
    if not (np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))):
        raise FloatingPointError(f"MuJoCo {what}: the state is not finite at t = {data.time:g}")


def _site_gap(data: Any, pairs: list[tuple[int, int]]) -> float:
    """The largest distance between the two sites of a connect: the loop closures' violation."""
    return max(float(np.linalg.norm(data.site_xpos[a] - data.site_xpos[b])) for a, b in pairs)


# ------------------------------------------------------------------------------------------------- four-bar


def four_bar_mjcf(
    l0: float = 1.0,
    l1: float = 0.3,
    l2: float = 1.0,
    l3: float = 0.8,
    rho: float = 1.0,
    g: float = 9.81,
    dt: float = DT,
) -> str:
    """Crank on a ground hinge at ``O``, coupler hinged at its tip ``B``, rocker hinged at ``C``: each bar along its
    body's ``x``, so the hinge angles are the scene's relative angles; a connect pins the rocker's end to ``P``."""
    return f"""
<mujoco model="four-bar">
  <option timestep="{dt}" integrator="RK4" gravity="0 {-g} 0"><flag contact="disable"/></option>
  <worldbody>
    <site name="P" pos="{l0} 0 0"/>
    <body name="crank">
      <joint name="theta1" type="hinge" axis="0 0 1"/>
      {_bar_inertial(l1, rho * l1, "x")}
      <body name="coupler" pos="{l1} 0 0">
        <joint name="theta2" type="hinge" axis="0 0 1"/>
        {_bar_inertial(l2, rho * l2, "x")}
        <body name="rocker" pos="{l2} 0 0">
          <joint name="theta3" type="hinge" axis="0 0 1"/>
          {_bar_inertial(l3, rho * l3, "x")}
          <site name="end" pos="{l3} 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
  <equality><connect site1="end" site2="P" {stiffest(dt)}/></equality>
</mujoco>"""


def four_bar(
    t_end: float = 2.0,
    dt: float = DT,
    budget: float = 0.2,
    repeats: int = 3,
    l0: float = 1.0,
    l1: float = 0.3,
    l2: float = 1.0,
    l3: float = 0.8,
    rho: float = 1.0,
    g: float = 9.81,
    theta0: float = math.pi / 2,
    omega0: float = 6.0,
) -> dict[str, float]:
    """The ``four-bar-redundant`` linkage from the scene's ``assemble`` state, ``t_end`` at ``dt``.

    Returns ``wall_ms`` (the whole run), ``step_us``, ``steps``, ``theta1`` (the crank angle at ``t_end``,
    unwrapped, comparable with gausspp's ``q[0]``), ``violation`` (``|end − P|`` at ``t_end``, m) and
    ``energy_drift`` (the relative change of the total energy: the soft closure's and RK4's work).
    """
    mujoco = _mujoco()
    model = mujoco.MjModel.from_xml_string(four_bar_mjcf(l0, l1, l2, l3, rho, g, dt))
    model.opt.enableflags |= mujoco.mjtEnableBit.mjENBL_ENERGY
    data = mujoco.MjData(model)
    q0, v0 = _four_bar.assemble(theta0, omega0, l0, l1, l2, l3)
    steps = round(t_end / dt)

    def start(d: Any) -> None:
        d.qpos[:], d.qvel[:] = q0, v0

    wall_us = _timed(mujoco, model, data, start, steps, budget, repeats)
    mujoco.mj_resetData(model, data)
    start(data)
    mujoco.mj_forward(model, data)
    energy0 = float(data.energy.sum())
    _finished(mujoco, model, data, start, steps, "four-bar")
    pair = [(model.site("end").id, model.site("P").id)]
    return dict(
        wall_ms=wall_us / 1e3,
        step_us=wall_us / steps,
        steps=steps,
        theta1=float(data.qpos[0]),
        violation=_site_gap(data, pair),
        energy_drift=abs(float(data.energy.sum()) - energy0) / abs(energy0),
    )


# ------------------------------------------------------------------------------------------------- box drop


def damping_ratio(e: float) -> float:
    """The damping ratio of a linear spring–damper contact whose rebound speed is ``e`` times the impact speed."""
    if e <= 0:
        return 1.0
    log = math.log(e)
    return -log / math.hypot(math.pi, log)


def box_drop_mjcf(
    m: float = 1.0,
    w: float = 0.4,
    h: float = 0.2,
    g: float = 9.81,
    e: float = 0.5,
    dt: float = DT,
    timeconst: float = 0.01,
) -> str:
    """The block (depth ``w`` along ``y``, inertia ``m (w² + h²)/12`` about ``y``) on slide x, slide z and a hinge
    about ``−y`` (``θ`` turns ``x`` towards ``z``, as the scene's), over a frictionless plane (``condim`` 1); the
    contact's ``solref = (timeconst, ζ)`` gives a spring–damper of damping ratio ``ζ`` = :func:`damping_ratio`."""
    moment = m * (w * w + h * h) / 12.0
    contact = f'condim="1" solref="{timeconst:g} {damping_ratio(e):.6g}" solimp="0.99 0.99 0.001 0.5 2"'
    return f"""
<mujoco model="box-drop">
  <option timestep="{dt}" integrator="RK4" gravity="0 0 {-g}"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" {contact}/>
    <body name="box">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <joint name="theta" type="hinge" axis="0 -1 0"/>
      <inertial pos="0 0 0" mass="{m}" diaginertia="{moment} {moment} {moment}"/>
      <geom name="block" type="box" size="{w / 2} {w / 2} {h / 2}" {contact}/>
    </body>
  </worldbody>
</mujoco>"""


def _first_bounce(
    mujoco: Any, model: Any, data: Any, start: Any, w: float, h: float, drop: float, t_end: float
) -> tuple[float, float]:
    """The first contact's time and the measured restitution ``√(apex / drop)`` of the first bounce, step by step:
    the apex of the block's lowest corner, ``z − (w/2)|sin θ| − (h/2) cos θ``, once the contacts have let go."""
    mujoco.mj_resetData(model, data)
    start(data)
    first_impact, apex, bounced = math.nan, -math.inf, False
    while data.time < t_end:
        mujoco.mj_step(model, data)
        _, z, th = data.qpos
        if data.ncon and math.isnan(first_impact):
            first_impact = float(data.time)
        if not math.isnan(first_impact):
            bounced = bounced or (data.ncon == 0 and data.qvel[1] > 0)
            if bounced:
                apex = max(apex, z - 0.5 * w * abs(math.sin(th)) - 0.5 * h * math.cos(th))
                if data.qvel[1] <= 0:
                    break
    return first_impact, (math.sqrt(max(apex, 0.0) / drop) if bounced and drop > 0 else 0.0)


def _calibrated(
    mujoco: Any, model: Any, data: Any, start: Any, w: float, h: float, drop: float, e: float, t_end: float
) -> float:
    """The contact damping ratio whose measured first bounce (:func:`_first_bounce`) has restitution ``e``:
    bisection between the linear spring–damper's ratio (a contact that only pushes, and the discrete step,
    bounce higher than it says) and 1."""
    low, high = damping_ratio(e), 1.0
    for _ in range(30):
        mid = 0.5 * (low + high)
        model.geom_solref[:, 1] = mid
        low, high = (mid, high) if _first_bounce(mujoco, model, data, start, w, h, drop, t_end)[1] > e else (low, mid)
        if high - low < 1e-4:
            break
    return 0.5 * (low + high)


def box_drop(
    t_end: float = 3.0,
    dt: float = DT,
    budget: float = 0.2,
    repeats: int = 3,
    m: float = 1.0,
    w: float = 0.4,
    h: float = 0.2,
    g: float = 9.81,
    e: float = 0.5,
    drop: float = 1.0,
    tilt: float = 0.0,
    vx: float = 0.0,
    timeconst: float = 0.01,
    calibrate: bool = True,
    rest_window: float = 0.5,
) -> dict[str, float]:
    """``block-on-floor`` (the scene's defaults): dropped with its lower corner ``drop`` above the floor.

    Returns ``wall_ms`` and ``step_us`` of the whole run, ``rest_step_us`` (one ``mj_step`` with the block
    resting on the floor, from the state at ``t_end``), ``restitution`` (measured: ``√(apex / drop)`` of the
    first bounce, the apex of the lowest corner), ``damping_ratio`` (the contact's ``solref[1]``: with
    ``calibrate``, bisected until the measured restitution is ``e``; otherwise :func:`damping_ratio`),
    ``first_impact`` (s; the scene's closed form is ``√(2 drop / g)``), over the last ``rest_window`` seconds
    ``rest_band`` (the largest ``|height|`` of the lowest corner, m), ``rest_speed`` (the largest ``|q̇|``
    component) and ``airborne`` (the fraction of steps without contact: the soft contact keeps the block
    hopping by micrometres at this ``dt``), ``contacts`` at ``t_end`` and
    ``violation`` (the deepest penetration at ``t_end``, m: MuJoCo's soft contact rests slightly in the floor).
    """
    mujoco = _mujoco()
    model = mujoco.MjModel.from_xml_string(box_drop_mjcf(m, w, h, g, e, dt, timeconst))
    data = mujoco.MjData(model)
    z0 = drop + 0.5 * w * abs(math.sin(tilt)) + 0.5 * h * math.cos(tilt)  # the scene's start
    steps = round(t_end / dt)

    def start(d: Any) -> None:
        d.qpos[:], d.qvel[:] = (0.0, z0, tilt), (vx, 0.0, 0.0)

    zeta = damping_ratio(e)
    if calibrate and 0 < e < 1:
        zeta = _calibrated(mujoco, model, data, start, w, h, drop, e, t_end)
    model.geom_solref[:, 1] = zeta
    first_impact, restitution = _first_bounce(mujoco, model, data, start, w, h, drop, t_end)
    wall_us = _timed(mujoco, model, data, start, steps, budget, repeats)
    # the last stretch step by step (untimed): how still the block rests
    tail = min(steps, round(rest_window / dt))
    mujoco.mj_resetData(model, data)
    start(data)
    mujoco.mj_step(model, data, steps - tail)
    band, speed, airborne = 0.0, 0.0, 0
    for _ in range(tail):
        mujoco.mj_step(model, data)
        _, z, th = data.qpos
        band = max(band, abs(z - 0.5 * w * abs(math.sin(th)) - 0.5 * h * math.cos(th)))
        speed = max(speed, float(np.abs(data.qvel).max()))
        airborne += data.ncon == 0
    mujoco.mj_forward(model, data)
    if not (np.all(np.isfinite(data.qpos)) and np.all(np.isfinite(data.qvel))):
        raise FloatingPointError(f"MuJoCo box drop: the state is not finite at t = {data.time:g}")
    contacts = int(data.ncon)
    violation = max([0.0] + [-float(data.contact[i].dist) for i in range(contacts)])
    rest_us = best_us(lambda: mujoco.mj_step(model, data), budget, repeats)
    if not np.all(np.isfinite(data.qpos)):
        raise FloatingPointError("MuJoCo box drop: the state is not finite after the resting steps")
    return dict(
        wall_ms=wall_us / 1e3,
        step_us=wall_us / steps,
        steps=steps,
        rest_step_us=rest_us,
        restitution=restitution,
        damping_ratio=zeta,
        first_impact=first_impact,
        contacts=contacts,
        rest_band=band,
        rest_speed=speed,
        airborne=airborne / tail,
        violation=violation,
    )


# ------------------------------------------------------------------------------------------- ladder of cells


def ladder_mjcf(n_cells: int, length: float = 1.0, mass: float = 1.0, g: float = 9.81, dt: float = DT) -> str:
    """``n_cells + 1`` cranks (bars along ``+y``) on ground hinges at ``x = i``; coupler ``i`` (a bar along ``+x``)
    hinged on crank ``i``'s tip, its end connected to crank ``i + 1``'s tip."""
    bodies = []
    for i in range(n_cells + 1):
        coupler = (
            f"""
      <body name="coupler{i}" pos="0 {length} 0">
        <joint type="hinge" axis="0 0 1"/>
        {_bar_inertial(length, mass, "x")}
        <site name="end{i}" pos="{length} 0 0"/>
      </body>"""
            if i < n_cells
            else ""
        )
        bodies.append(
            f"""
    <body name="crank{i}" pos="{i * length} 0 0">
      <joint type="hinge" axis="0 0 1"/>
      {_bar_inertial(length, mass, "y")}
      <site name="tip{i}" pos="0 {length} 0"/>{coupler}
    </body>"""
        )
    connects = "".join(f'\n    <connect site1="end{i}" site2="tip{i + 1}" {stiffest(dt)}/>' for i in range(n_cells))
    return f"""
<mujoco model="ladder-{n_cells}">
  <option timestep="{dt}" integrator="RK4" gravity="0 {-g} 0"><flag contact="disable"/></option>
  <worldbody>{"".join(bodies)}
  </worldbody>
  <equality>{connects}
  </equality>
</mujoco>"""


def parallelogram_ladder(
    n_cells: int,
    t_end: float = 1.0,
    dt: float = DT,
    budget: float = 0.2,
    repeats: int = 3,
    speed: float = 1.0,
    length: float = 1.0,
    mass: float = 1.0,
    g: float = 9.81,
) -> dict[str, float]:
    """``n_cells`` parallelogram cells from the vertical, every crank tip moving at ``speed`` along ``+x``.

    Cranks and couplers are uniform bars of ``mass`` and ``length``. Returns ``wall_ms``, ``step_us``, ``steps``,
    ``nv`` (hinges), ``rows`` (equality rows: 3 per connect, the out-of-plane one identically 0), ``angle``
    (crank 0's turn from the vertical at ``t_end``, rad, clockwise positive), ``angle_error`` (``angle`` minus
    :func:`ladder_reference`'s; the cranks pass the collinear, singular position at a quarter turn), ``spread``
    (the largest difference of the cranks' angles at ``t_end``: 0 for a rigid parallelogram ladder) and
    ``violation`` (the largest ``|end_i − tip_{i+1}|`` at ``t_end``, m).
    """
    mujoco = _mujoco()
    model = mujoco.MjModel.from_xml_string(ladder_mjcf(n_cells, length, mass, g, dt))
    data = mujoco.MjData(model)
    cranks = np.array([model.joint(model.body(f"crank{i}").jntadr[0]).qposadr[0] for i in range(n_cells + 1)])
    couplers = np.array([model.joint(model.body(f"coupler{i}").jntadr[0]).qposadr[0] for i in range(n_cells)])
    steps = round(t_end / dt)
    omega = speed / length

    def start(d: Any) -> None:
        d.qvel[cranks] = -omega  # clockwise: the tips (0, L) move along +x
        d.qvel[couplers] = omega  # the couplers keep level

    wall_us = _timed(mujoco, model, data, start, steps, budget, repeats)
    _finished(mujoco, model, data, start, steps, f"ladder N={n_cells}")
    pairs = [(model.site(f"end{i}").id, model.site(f"tip{i + 1}").id) for i in range(n_cells)]
    angles = -data.qpos[cranks]
    return dict(
        wall_ms=wall_us / 1e3,
        step_us=wall_us / steps,
        steps=steps,
        nv=int(model.nv),
        rows=3 * n_cells,
        angle=float(angles[0]),
        angle_error=float(angles[0]) - ladder_reference(n_cells, t_end, speed, length, mass, g),
        spread=float(angles.max() - angles.min()),
        violation=_site_gap(data, pairs),
    )


def ladder_reference(
    n_cells: int, t_end: float = 1.0, speed: float = 1.0, length: float = 1.0, mass: float = 1.0, g: float = 9.81
) -> float:
    """Crank 0's turn from the vertical at ``t_end`` (rad, clockwise) on the ladder's one-DOF model: every crank at
    the angle ``θ`` from the ground line, every coupler translating with the tips, so ``I θ̈ = −G cos θ`` with
    ``I = (n/3 + N) m l²``, ``G = g m l (n/2 + N)``, ``n = N + 1`` cranks; ``θ(0) = π/2``, ``θ̇(0) = −speed/l``
    (DOP853 at ``rtol = atol = 1e-12``)."""
    from scipy.integrate import solve_ivp

    n = n_cells + 1
    inertia = (n / 3 + n_cells) * mass * length**2
    moment = g * mass * length * (n / 2 + n_cells)
    sol = solve_ivp(
        lambda _t, s: [s[1], -moment * math.cos(s[0]) / inertia],
        (0.0, t_end),
        [math.pi / 2, -speed / length],
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
    )
    return math.pi / 2 - float(sol.y[0, -1])


def growth_exponent(sizes: list[int], times: list[float]) -> float:
    """The least-squares slope ``p`` of ``log time = p log size + c``."""
    return float(np.polyfit(np.log(sizes), np.log(times), 1)[0])
