"""Tolerances that mean the same at every scale (issue 42): at rest, in small motions, in other units.

Every tolerance of a run is measured against a scale read from the machine (:mod:`gausspp.model.run_scales`):
a pendulum hanging at rest, released 1e-9 rad from it, or rewritten in millimetres, runs with the status and the
relative accuracy it has in metres."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gausspp as gp
from gausspp.model import run_scales as run_scales_module
from gausspp.model.run_scales import row_scales, run_scales

L, EQUILIBRIUM = 1.0, -np.pi / 2  # the pendulum scene: arm of 1 m, hanging at φ = −π/2


def hanging(delta: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The pendulum scene's state ``delta`` rad from hanging, at rest (centre of mass at ``L(cos φ, sin φ)``)."""
    phi = EQUILIBRIUM + delta
    return np.array([L * np.cos(phi), L * np.sin(phi), phi]), np.zeros(3)


LANES = [
    dict(),
    dict(method="RK45"),
    dict(method="Radau"),
    dict(method="BDF"),
    dict(method="rk4", dt=1e-3),
    dict(method="rk4", dt=1e-3, lane="python"),
    dict(method="symplectic-euler", dt=1e-3),
    dict(method="cvodes", solver="direct"),
    dict(method="cvodes-adams", solver="direct"),
]


@pytest.mark.parametrize("solver", ["qp", "direct"])
@pytest.mark.parametrize("options", LANES, ids=lambda o: "-".join(f"{v}" for v in o.values()) or "defaults")
def test_the_pendulum_hanging_at_rest_is_a_success_in_every_lane(solver: str, options: dict) -> None:
    """Was: ``DriftError`` at t = 1e-4 — an energy balance of −1.8e-39 J judged against an energy scale of 3.6e-39 J
    (the kinetic energy of round-off). Now the balance is judged above its round-off floor (the pendulum's weight
    times its size), and the rows against their own scales."""
    scene = gp.scenes.get("pendulum")
    q0, v0 = hanging()
    options = {"solver": solver, **options}
    traj = gp.simulate(scene.model, q0, v0, 2.0, **options)
    assert traj.status == "success", traj.message
    assert traj.t[-1] == 2.0
    assert np.abs(traj.q - q0).max() < 1e-9  # it stays where it hangs


def measured_period(t: np.ndarray, x: np.ndarray) -> float:
    """Twice the mean time between the zero crossings of ``x`` (each crossing by linear interpolation)."""
    sign = np.sign(x)
    i = np.flatnonzero(sign[:-1] * sign[1:] < 0)
    crossings = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    assert crossings.size >= 6, "too few half-periods to measure"
    return 2.0 * float(np.mean(np.diff(crossings)))


def linear_period(model: gp.Model) -> float:
    q, v = hanging()
    lin = gp.linearize(model, 0.0, q, v)
    return 2 * np.pi / float(np.abs(lin.eigenvalues.imag).max())


@pytest.mark.parametrize("amplitude", [1e-9, 1e-6, 1e-3, 1e-1])
def test_released_near_rest_it_swings_with_the_linearized_period(amplitude: float) -> None:
    """Released at 1e-9 … 1e-1 rad, at the defaults: a success, and at the small amplitudes the period measured from
    the recorded swing (the zero crossings of ``x``) is ``2π/ω`` of ``gp.linearize`` to 1e-6 (measured 1.6e-7 at
    1e-9 rad, 1.6e-10 at 1e-6, 6.3e-8 at 1e-3 — the pendulum's own θ²/16). The default absolute tolerance is rtol
    times each coordinate's size, so the 1e-9 rad swing is followed to rtol of itself (an absolute 1e-10 made it
    1.8e-4)."""
    scene = gp.scenes.get("pendulum")
    period = linear_period(scene.model)
    q0, v0 = hanging(amplitude)
    t_end = 5 * period
    traj = gp.simulate(scene.model, q0, v0, t_end, record=np.linspace(0.0, t_end, 20001))
    assert traj.status == "success", traj.message
    if amplitude <= 1e-3:
        assert abs(measured_period(traj.t, traj.q[:, 0]) / period - 1) <= 1e-6


def test_the_period_check_tells_a_longer_arm_apart() -> None:
    """The control: the same measurement on a pendulum whose arm is 1e-5 longer is off the period by more than 1e-6."""
    period = linear_period(gp.scenes.get("pendulum").model)
    longer = gp.scenes.get("pendulum", L=1.0 + 1e-5)
    phi = EQUILIBRIUM + 1e-6
    q0 = np.array([(1 + 1e-5) * np.cos(phi), (1 + 1e-5) * np.sin(phi), phi])
    t_end = 5 * period
    traj = gp.simulate(longer.model, q0, np.zeros(3), t_end, record=np.linspace(0.0, t_end, 20001))
    assert abs(measured_period(traj.t, traj.q[:, 0]) / period - 1) > 1e-6


def test_the_old_absolute_tolerance_misses_the_small_swing() -> None:
    """The control of the default: an absolute atol of 1e-10 follows the 1e-9 rad swing to 1e-4 of its period only."""
    scene = gp.scenes.get("pendulum")
    period = linear_period(scene.model)
    q0, v0 = hanging(1e-9)
    t_end = 5 * period
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.DriftWarning)
        traj = gp.simulate(scene.model, q0, v0, t_end, atol=1e-10, record=np.linspace(0.0, t_end, 20001), throw=False)
    assert abs(measured_period(traj.t, traj.q[:, 0]) / period - 1) > 1e-5


def spring(k: float = 4.0, m: float = 1.0) -> gp.Model:
    mech = gp.Lagrangian(n=1, T=lambda q, v, t: 0.5 * m * v[0] ** 2, V=lambda q, t: 0.5 * k * q[0] ** 2)
    return gp.Model(mech, [])


@pytest.mark.parametrize("displacement", [0.0, 1e-8, 1e-3, 1.0])
def test_a_mass_on_a_spring_near_its_equilibrium(displacement: float) -> None:
    """Was ``"drifted"`` at 1e-8 m: the balance's round-off against the kinetic energy of a 1e-8 m swing. The motion
    is ``x₀ cos 2t`` to rtol of its amplitude at every amplitude."""
    traj = gp.simulate(spring(), [displacement], [0.0], 3.0, record=np.linspace(0.0, 3.0, 31))
    assert traj.status == "success", traj.message
    exact = displacement * np.cos(2.0 * traj.t)
    assert np.abs(traj.q[:, 0] - exact).max() <= 1e-8 * displacement


def test_the_parallelogram_four_bar_of_bodies_and_joints_hangs_at_rest() -> None:
    """IFToMM A02 written with ``gp.Multibody``, cranks hanging straight down: was ``"drifted"``."""
    G = 9.81
    mb = gp.Multibody(gravity=(0.0, -G))
    bar = dict(mass=1.0, inertia=1.0 / 12)
    mb.body("crank1", **bar, at=(0.0, -0.5), angle=-np.pi / 2)
    mb.body("coupler", **bar, at=(0.5, -1.0), angle=0.0)
    mb.body("crank2", **bar, at=(1.0, -0.5), angle=-np.pi / 2)
    mb.revolute("ground-crank1", "crank1", (-0.5, 0.0), None, (0.0, 0.0))
    mb.revolute("crank1-coupler", "crank1", (0.5, 0.0), "coupler", (-0.5, 0.0))
    mb.revolute("coupler-crank2", "coupler", (0.5, 0.0), "crank2", (0.5, 0.0))
    mb.revolute("ground-crank2", "crank2", (-0.5, 0.0), None, (1.0, 0.0))
    q0, v0 = mb.assemble(fix={"crank1.θ": -np.pi / 2}, rates={"crank1.θ̇": 0.0})
    traj = gp.simulate(mb.model(), q0, v0, 2.0)
    assert traj.status == "success", traj.message
    assert np.abs(traj.q - q0).max() < 1e-9


def test_a_crane_holding_its_payload_still_is_a_success() -> None:
    """A servo-constraint with a constant target, reached through higher derivatives (the servo lane): no kinetic
    energy, no work exchanged — was ``"drifted"`` by a balance of 3e-18 judged against a scale of zero."""
    scene = gp.scenes.get("overhead-crane", D=0.0, h=0.0)  # the flat-output crane: its payload's path held still
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 4.0)
    assert traj.status == "success", traj.message
    assert np.abs(traj.q - scene.q0).max() < 1e-9


def particle_on_circle() -> gp.Model:
    """A particle on a circle of radius 2 in the plane ``(x, y)`` and an unrelated free coordinate ``w``."""
    mech = gp.Lagrangian(n=3, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2 + v[2] ** 2), V=lambda q, t: 9.81 * q[1])
    return gp.Model(mech, [gp.Holonomic(lambda q, t: q[0] ** 2 + q[1] ** 2 - 4.0, name="circle")])


def test_a_row_is_judged_against_its_own_scale_not_the_largest_coordinate() -> None:
    """The tolerance module's scales of the circle's row are those of ``x, y`` alone: the same whether the unrelated
    coordinate ``w`` is 0 or 1e6 (with ``1 + ‖q‖∞`` the row's tolerance grew a million times)."""
    model = particle_on_circle()
    t, v = np.array([0.0]), np.array([0.0, 0.0, 0.0])
    found = []
    for w in (0.0, 1e6):
        q = np.array([2.0, 0.0, w])
        scales = run_scales(model, 0.0, q, v, np.zeros(0), 1.0)
        s_g, s_Phi, floor_g, floor_Phi = row_scales(model, scales, t, np.concatenate([q, v])[None, :], 1)
        found.append((s_g[0, 0], s_Phi[0, 0], floor_g[0, 0], floor_Phi[0, 0]))
    np.testing.assert_allclose(found[0], found[1], rtol=1e-12)
    assert found[0][0] == pytest.approx(8.0)  # |∂g/∂x|·|x| = 4·2: the row's own terms


def test_initial_data_off_the_row_are_refused_whatever_an_unrelated_coordinate() -> None:
    """1e-3 off the circle is refused with ``w = 1e6`` as with ``w = 0`` (relative to ``1 + ‖q‖∞`` it passed)."""
    model = particle_on_circle()
    for w in (0.0, 1e6):
        with pytest.raises(gp.InitialDataError, match="circle"):
            gp.simulate(model, [2.0 + 1e-3, 0.0, w], [0.0, 0.0, 0.0], 1.0)
        traj = gp.simulate(model, [2.0, 0.0, w], [0.0, 0.0, 0.0], 1.0)  # on the circle: a success
        assert traj.status == "success", traj.message


def test_the_scales_do_not_depend_on_an_arbitrary_zero_of_the_potential() -> None:
    """The energy scale reads the potential's range over the run, not its value: the pendulum released at 1e-3 rad
    with ``V`` shifted by 1e3 J keeps its status and its motion (only the round-off floor grows with |E|, as
    round-off does)."""
    scene = gp.scenes.get("pendulum")
    q0, v0 = hanging(1e-3)
    runs = []
    for zero in (0.0, 1e3):
        body = gp.Lagrangian(
            n=3,
            T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2) + 0.5 * 0.01 * v[2] ** 2,
            V=lambda q, t, zero=zero: 9.81 * q[1] + zero,
        )
        runs.append(gp.simulate(gp.Model(body, list(scene.model.constraints)), q0, v0, 2.0))
    assert runs[0].status == runs[1].status == "success"
    np.testing.assert_allclose(runs[1].q, runs[0].q, atol=1e-12)


def test_every_scale_is_positive_and_finite_at_rest() -> None:
    """A machine at rest has scales that do not vanish: a floor from its weight times its size."""
    scene = gp.scenes.get("pendulum")
    q, v = hanging()
    s = run_scales(scene.model, 0.0, q, v, np.zeros(0), 2.0)
    for values in (s.q, s.v, s.floor_q, s.floor_v, s.atol(1e-10)):
        assert np.all(np.isfinite(values)) and np.all(values > 0)
    assert s.energy_floor(np.array([0.0]))[0] > 0
    assert run_scales_module.CHECK_ROUNDOFF < 1e-8  # the floors stay far below any tolerance a run asks for


def test_a_contact_penetrated_by_a_millimetre_is_refused_whatever_a_far_coordinate() -> None:
    """``gp.simulate_friction`` judges each gap against its own terms: a box's corners 1 mm into the floor are refused
    with its ``x`` at 2e5 m as at 0 (relative to ``1 + ‖q‖∞`` the tolerance grew to 2 mm and let them in); resting on
    the floor it starts."""
    from gausspp.friction import scenes as friction_scenes

    mech, contacts = friction_scenes.box(0.3)
    for x in (0.0, 2e5):
        with pytest.raises(gp.InitialDataError, match="penetrate"):
            gp.simulate_friction(mech, contacts, [x, 0.1 - 1e-3, 0.0], [0.0, 0.0, 0.0], 0.1)
        run = gp.simulate_friction(mech, contacts, [x, 0.1, 0.0], [0.0, 0.0, 0.0], 0.1)
        assert run.t[-1] == pytest.approx(0.1)
