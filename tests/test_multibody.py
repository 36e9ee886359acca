"""gp.Multibody (issue 31): machines written as bodies and joints, against references that share nothing with
gausspp's step — a one-degree-of-freedom model solved by scipy (the parallelogram, the slider-crank by sympy's
Lagrange equation, the swinging rod), and the hand-written scene of the same parallelogram."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import gausspp as gp
from gausspp.scenes import parallelogram as P

G = 9.81
ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("bodies_and_joints", ROOT / "examples" / "bodies_and_joints.py")
assert _spec is not None and _spec.loader is not None
example = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(example)


def four_bar() -> tuple[gp.Multibody, np.ndarray, np.ndarray]:
    """IFToMM A02 as the gallery writes it (examples/bodies_and_joints.py), the first crank's tip moving at 1 m/s
    along −x (``θ̇ = −1``)."""
    mb = example.four_bar()
    q0, v0 = mb.assemble(fix={"crank1.θ": np.pi / 2}, rates={"crank1.θ̇": -1.0})
    return mb, q0, v0


def test_the_four_bar_through_its_collinear_positions_against_the_one_dof_model() -> None:
    """10 s at rtol = atol = 1e-12: every collinear position passed (10), the crank tip within 1e-8 m of the
    one-DOF reference (measured 8.5e-12), energy constant to 1e-9 (measured 3e-13), and the same motion as the
    hand-written scene to 1e-10 (measured 2.3e-11)."""
    mb, q0, v0 = four_bar()
    model = mb.model()
    assert "revolute crank1-coupler [x]" in model.names
    traj = gp.simulate(model, q0, v0, 10.0, rtol=1e-12, atol=1e-12)
    assert traj.success and sum(e["kind"] == "singular position" for e in traj.events) == 10
    scene = gp.scenes.get("parallelogram")
    theta, _omega = P.one_dof_reference(traj.t, **scene.params)
    tip = traj.q[:, 0:2] + 0.5 * np.column_stack([np.cos(traj.q[:, 2]), np.sin(traj.q[:, 2])])
    assert np.abs(tip - np.column_stack([np.cos(theta), np.sin(theta)])).max() <= 1e-8
    assert np.ptp(traj.energy) <= 1e-9 * np.abs(traj.energy).max()
    hand = gp.simulate(scene.model, scene.q0, scene.v0, 10.0, rtol=1e-12, atol=1e-12, record=traj.t)
    assert np.abs(hand.q - traj.q).max() <= 1e-10 * (1 + np.abs(hand.q).max())
    assert np.abs(q0 - scene.q0).max() <= 1e-14 and np.abs(v0 - scene.v0).max() <= 1e-14  # the same assembly


def test_the_slider_crank_against_lagrange_in_the_crank_angle() -> None:
    """Crank 0.5 m, rod 1.2 m, slider on a guide through the crank's pin: the crank angle within 1e-9 rad of the
    one-DOF Lagrange equation (measured 1.8e-11), energy to 1e-9 (measured 7e-11); the slider stays on its guide."""
    pytest.importorskip("sympy")
    mb = example.slider_crank()
    q0, v0 = mb.assemble(fix={"crank.θ": np.pi / 2}, rates={"crank.θ̇": 2.0})
    traj = gp.simulate(mb.model(), q0, v0, 3.0, rtol=1e-12, atol=1e-12, record=np.linspace(0.0, 3.0, 61))
    assert traj.success
    theta = example.slider_crank_reference(traj.t)
    assert np.abs(traj.q[:, 2] - theta).max() <= 1e-9
    assert np.ptp(traj.energy) <= 1e-9 * np.abs(traj.energy).max()
    assert np.abs(traj.q[:, 7]).max() <= 1e-10 and np.abs(traj.q[:, 8]).max() <= 1e-10  # y and angle of the slider
    wrong = example.slider_crank_reference(traj.t, L=1.2 * (1 + 1e-6))  # the negative control
    assert np.abs(traj.q[:, 2] - wrong).max() > 100 * 1e-9


def _rod(kind: str) -> tuple[gp.Model, np.ndarray, np.ndarray]:
    """A uniform rod of 1 m and 1 kg (a spatial body, axis along its body z) hung from its end by a ball joint or a
    hinge about y, released 0.6 rad from the vertical (gravity −z)."""
    th0 = 0.6
    R = np.array([[np.cos(th0), 0.0, np.sin(th0)], [0.0, 1.0, 0.0], [-np.sin(th0), 0.0, np.cos(th0)]])
    mb = gp.Multibody(gravity=(0.0, 0.0, -G))
    mb.body("rod", mass=1.0, inertia=(1 / 12, 1 / 12, 1e-4), at=-R @ [0, 0, 0.5],
            orientation=(np.cos(th0 / 2), 0.0, np.sin(th0 / 2), 0.0))  # fmt: skip
    if kind == "spherical":
        mb.spherical("pivot", "rod", (0.0, 0.0, 0.5), None, (0.0, 0.0, 0.0))
    else:
        mb.revolute("hinge", "rod", (0.0, 0.0, 0.5), None, (0.0, 0.0, 0.0), axis=(0.0, 1.0, 0.0))
    q0, v0 = mb.assemble()
    return mb.model(), q0, v0


@pytest.mark.parametrize("kind", ["spherical", "revolute"])
def test_a_spatial_rod_swings_as_the_pendulum_and_keeps_its_quaternion(kind: str) -> None:
    """The centre within 1e-9 m of the compound pendulum ``θ̈ = −(m g L/2) sin θ / (m L²/3)`` (measured 2.7e-12),
    the quaternion of unit length to 1e-12 with no norm row, energy to 1e-9 (measured 1e-11)."""
    model, q0, v0 = _rod(kind)
    assert model.k == (3 if kind == "spherical" else 5)
    traj = gp.simulate(model, q0, v0, 5.0, rtol=1e-12, atol=1e-12, record=np.linspace(0.0, 5.0, 51))
    sol = solve_ivp(lambda _t, s: [s[1], -G * 0.5 * np.sin(s[0]) / (1 / 3)], (0, 5), [0.6, 0.0], t_eval=traj.t,
                    method="DOP853", rtol=1e-13, atol=1e-13)  # fmt: skip
    centre = np.column_stack([-0.5 * np.sin(sol.y[0]), np.zeros_like(traj.t), -0.5 * np.cos(sol.y[0])])
    assert np.abs(traj.q[:, :3] - centre).max() <= 1e-9
    assert np.abs(np.linalg.norm(traj.q[:, 3:7], axis=1) - 1.0).max() <= 1e-12
    assert np.ptp(traj.energy) <= 1e-9 * np.abs(traj.energy).max()


def test_a_tumbling_brick_keeps_its_invariants_without_any_row() -> None:
    """A free spatial body (no joint): A = diag(m, m, m, J) constant and positive definite, the quaternion of unit
    length, energy and the body's angular momentum magnitude |Jω| conserved (Euler's equations)."""
    mb = gp.Multibody(gravity=(0.0, 0.0, -G))
    mb.body("brick", mass=2.0, inertia=(1.0, 2.0, 2.5), at=(0.0, 0.0, 0.0))
    model = mb.model()
    A = model.step_data(0.0, np.r_[0, 0, 0, 1.0, 0, 0, 0], np.zeros(6)).A
    assert model.k == 0 and np.allclose(np.linalg.eigvalsh(A), [1, 2, 2, 2, 2, 2.5])
    traj = gp.simulate(model, [0, 0, 0, 1.0, 0, 0, 0], [1.0, 0.0, 5.0, 0.1, 3.0, 0.2], 10.0, rtol=1e-12, atol=1e-12)
    J = np.diag([1.0, 2.0, 2.5])
    momentum = np.linalg.norm(traj.v[:, 3:6] @ J, axis=1)
    assert np.abs(np.linalg.norm(traj.q[:, 3:7], axis=1) - 1.0).max() <= 1e-12
    assert np.ptp(traj.energy) <= 1e-9 * np.abs(traj.energy).max() and np.ptp(momentum) <= 1e-9 * momentum.max()


def test_assembly_holds_what_is_given_and_says_what_cannot_be_met() -> None:
    mb, q0, v0 = four_bar()
    g = np.array([np.asarray(c.value(q0, 0.0), float).ravel() for c in mb.constraints]).ravel()
    assert np.abs(g).max() <= 1e-13
    with pytest.raises(gp.InitialDataError, match="cannot be met"):
        mb.assemble(fix={"crank1.θ": np.pi / 2, "crank2.θ": 0.0})  # a parallelogram's cranks stay parallel
    with pytest.raises(gp.UnknownNameError, match="crank9"):
        mb.assemble(fix={"crank9.θ": 0.0})
    with pytest.raises(gp.InitialDataError, match="contradict"):
        mb.assemble(rates={"crank1.θ̇": 1.0, "crank2.θ̇": -1.0})


def test_bad_bodies_and_joints_are_refused_with_their_names() -> None:
    mb = gp.Multibody(gravity=(0.0, -G))
    with pytest.raises(gp.InputError, match="mass must be > 0"):
        mb.body("bar", mass=-1.0, inertia=1.0, at=(0, 0))
    mb.body("bar", mass=1.0, inertia=1.0, at=(0, 0))
    with pytest.raises(gp.InputError, match="exists already"):
        mb.body("bar", mass=1.0, inertia=1.0, at=(0, 0))
    with pytest.raises(gp.UnknownNameError, match="no body 'rod'"):
        mb.revolute("pin", "bar", (0, 0), "rod", (0, 0))
    with pytest.raises(gp.InputError, match="spatial machine"):
        mb.spherical("ball", "bar", (0, 0), None, (0, 0))
    with pytest.raises(gp.ShapeError, match="vector of 2"):
        mb.revolute("pin", "bar", (0, 0, 0), None, (0, 0))
    spatial = gp.Multibody(gravity=(0.0, 0.0, -G))
    with pytest.raises(gp.InputError, match="triangle"):
        spatial.body("odd", mass=1.0, inertia=(1.0, 1.0, 5.0), at=(0, 0, 0))


def test_a_motor_keeps_the_crank_on_its_law_with_the_torque_gravity_asks() -> None:
    """A crank (a bar on a ground pin) turned at 2 rad/s from the horizontal by a motor between ground and crank
    (a servo-constraint, the torque its reaction): the angle follows the law, and the torque is the one of the
    closed form ``(m g L/2) cos θ`` (uniform speed: no inertia term)."""
    mb = gp.Multibody(gravity=(0.0, -G))
    mb.body("crank", mass=1.0, inertia=1.0 / 12, at=(0.5, 0.0), angle=0.0)
    mb.revolute("ground-crank", "crank", (-0.5, 0.0), None, (0.0, 0.0))
    mb.motor("drive", None, "crank", lambda t: 2.0 * t)
    q0, v0 = mb.assemble(rates={"crank.θ̇": 2.0})
    traj = gp.simulate(mb.model(), q0, v0, 2.0, record=np.linspace(0.0, 2.0, 21))
    assert np.abs(traj.q[:, 2] - 2.0 * traj.t).max() <= 1e-8
    torque = traj.u[:, -1]
    assert np.abs(torque - G * 0.5 * np.cos(traj.q[:, 2])).max() <= 1e-8


def test_the_drawing_animates() -> None:
    pytest.importorskip("matplotlib")
    mb, q0, _v0 = four_bar()
    pic = mb.drawing(q0)
    assert len(pic["segments"]) == 6 and len(pic["fixed"]) == 2
    np.testing.assert_allclose(pic["fixed"][1], [1.0, 0.0])


def test_a_rate_given_by_its_coordinates_name_sets_that_velocity() -> None:
    """Spatial bodies have 7 coordinates and 6 velocities: ``b.x`` is ``b.ẋ`` of body ``b``, and a quaternion
    coordinate has no rate of its own (an error naming it)."""
    mb = gp.Multibody(gravity=(0.0, 0.0, -G))
    mb.body("a", mass=1.0, inertia=(1.0, 1.0, 1.0), at=(0, 0, 0))
    mb.body("b", mass=1.0, inertia=(1.0, 1.0, 1.0), at=(1, 0, 0))
    _q, v = mb.assemble(rates={"b.x": 1.0})
    assert v[mb.velocity_names.index("b.ẋ")] == 1.0 and np.count_nonzero(v) == 1
    with pytest.raises(gp.UnknownNameError, match="a.qz"):
        mb.assemble(rates={"a.qz": 1.0})


def test_an_overconstrained_spatial_loop_moves_with_its_one_degree_of_freedom() -> None:
    """The spatial double parallelogram from four spatial bars and six hinges: 30 rows, 24 velocities, rank 23
    (Bricard-size redundancy); through its collinear positions for 5 s at rtol = atol = 1e-11, the first crank's
    centre within 1e-8 m of the one-DOF model (measured 4.5e-10), out of its plane by nothing, energy to 1e-9
    (measured 4e-11). At the defaults (1e-10) the error is the tolerance's: 1.3e-8 m, energy 1.1e-9."""
    mb = example.spatial_double_parallelogram()
    model = mb.model()
    q0, v0 = mb.assemble(rates={"crank1.ωz": -1.0})
    assert (model.k, model.nv) == (30, 24)
    traj = gp.simulate(model, q0, v0, 5.0, record=np.linspace(0.0, 5.0, 101), rtol=1e-11, atol=1e-11)
    assert traj.success
    theta, _ = P.one_dof_reference(traj.t, third_bar=True)
    assert np.abs(traj.q[:, :2] - 0.5 * np.column_stack([np.cos(theta), np.sin(theta)])).max() <= 1e-8
    assert np.abs(traj.q[:, 2::7]).max() <= 1e-12
    assert np.ptp(traj.energy) <= 1e-9 * np.abs(traj.energy).max()


def test_bricards_mechanism_moves_as_mujoco_moves_it() -> None:
    """IFToMM A04 from bodies and joints (30 rows, rank 29) released from rest for 2 s, against MuJoCo's simulation
    of the same machine in joint coordinates (RK4, dt = 1e-4, the loop closed by soft connects): the link centres
    within 1e-7 m of each other (measured 5.6e-10) along a motion of 1.9 m; energy constant to 1e-9 (measured 3e-12).
    The negative control: a link 1 % heavier in gausspp is told apart."""
    mujoco = pytest.importorskip("mujoco")
    dt, times = 1e-4, np.linspace(0.1, 2.0, 20)
    mj_model = mujoco.MjModel.from_xml_string(example.bricard_mjcf(dt))
    data = mujoco.MjData(mj_model)
    centres = []
    for k in range(round(2.0 / dt)):
        mujoco.mj_step(mj_model, data)
        if (k + 1) % 1000 == 0:
            centres.append(data.xipos[1:6].copy())
    reference = np.array(centres)

    def run(mb: gp.Multibody) -> np.ndarray:
        model = mb.model()
        q0, v0 = mb.assemble()
        traj = gp.simulate(model, q0, v0, 2.0, rtol=1e-12, atol=1e-12, record=times)
        assert np.ptp(traj.energy) <= 1e-9 * np.abs(traj.energy).max()
        at = np.isin(traj.t, times)
        return np.stack([traj.q[at, 7 * i : 7 * i + 3] for i in range(5)], axis=1)

    mb = example.bricard()
    assert (mb.model().k, mb.model().nv) == (30, 30)
    ours = run(mb)
    assert np.abs(ours - ours[0]).max() > 1.0  # it moves
    assert np.abs(ours - reference).max() <= 1e-7
    assert np.abs(run(example.bricard(masses=(1.0, 1.0, 1.01, 1.0, 1.0))) - reference).max() > 1e2 * 1e-7


def test_a_prescribed_spin_is_kept_by_a_torque_about_its_axis() -> None:
    """A rod on a vertical hinge spun up by ``Multibody.spin`` at ω = 2t about its hinge axis: the rate follows the
    law, and the torque is the one of the closed form ``I_z ω̇ = 2 I_z`` (``I_z`` about the hinge: m L²/3)."""
    mb = gp.Multibody(gravity=(0.0, 0.0, -G))
    mb.body("rod", mass=1.0, inertia=(1e-4, 1.0 / 12, 1.0 / 12), at=(0.5, 0.0, 0.0))
    mb.revolute("hinge", "rod", (-0.5, 0.0, 0.0), None, (0.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0))
    mb.spin("drive", "rod", (0.0, 0.0, 1.0), lambda t: 2.0 * t)
    q0, v0 = mb.assemble()
    traj = gp.simulate(mb.model(), q0, v0, 1.0, record=np.linspace(0.0, 1.0, 11))
    assert np.abs(traj.v[:, 5] - 2.0 * traj.t).max() <= 1e-8
    assert np.abs(traj.u[:, -1] - 2.0 / 3.0).max() <= 1e-8


def test_a_planar_revolute_with_an_axis_and_bad_numbers_are_refused() -> None:
    mb = gp.Multibody(gravity=(0.0, -G))
    mb.body("bar", mass=1.0, inertia=1.0, at=(0, 0))
    with pytest.raises(gp.InputError, match="give no axis"):
        mb.revolute("pin", "bar", (0, 0), None, (0, 0), axis=(0, 0, 1))
    with pytest.raises(gp.NonFiniteError, match="at"):
        mb.body("nan", mass=1.0, inertia=1.0, at=(np.nan, 0))
    with pytest.raises(gp.InputError, match="gravity"):
        gp.Multibody(gravity=(0.0, np.inf))


# -- Watt's flyball governor: a spatial loop turned by a servo-constraint ---------------------------------------
def _governor_reduced(omega: float) -> tuple:
    """The governor in its one coordinate ``α`` (the arms' angle from the spindle), derived by hand from its
    geometry, no gausspp code: with the spin prescribed, ``L = ½ M(α) α̇² − U(α)``, ``U = V − ½ Ω² I_zz(α)``
    (Routh's effective potential; no cross terms: the hinges' axes are principal axes of the rods)."""
    h = 1.0

    def U(a: float) -> float:
        s2, c = np.sin(a) ** 2, np.cos(a)
        V = G * (2 * (h - 0.5 * c) + 2 * 0.5 * (h - 0.75 * c) + 0.5 * (h - c))  # arms, links, sleeve
        Izz = 2 * (0.25 * s2 + 1e-4 * c**2 + s2 / 12) + 2 * (0.5 * s2 / 16 + 0.5e-4 * c**2 + 0.5 * 0.25 / 12 * s2)
        return V - 0.5 * omega**2 * Izz

    def M(a: float) -> float:  # arms about their hinges, links (centre and turn), the sleeve's slide
        return 2 / 3 + 2 * (0.5 / 16 * (np.cos(a) ** 2 + 9 * np.sin(a) ** 2) + 0.5 * 0.25 / 12) + 0.5 * np.sin(a) ** 2

    def d(f: object, a: float, e: float = 1e-6) -> float:
        return (f(a + e) - f(a - e)) / (2 * e)  # type: ignore[operator]

    def rhs(t: float, y: np.ndarray) -> list[float]:
        return [y[1], -(0.5 * d(M, y[0]) * y[1] ** 2 + d(U, y[0])) / M(y[0])]

    return U, M, d, rhs


@pytest.mark.parametrize("offset", [0.0, 0.05], ids=["steady", "perturbed"])
def test_the_flyball_governor_turns_as_its_one_coordinate_model(offset: float) -> None:
    """Watt's governor at Ω = 7 rad/s (41 rows, rank 35; its loops' out-of-plane rows change from world y to world x
    components every quarter turn, where the rows kept are chosen anew): at the angle where the effective potential
    is stationary it stays (α* = 0.9262290591); 0.05 rad off, it swings as the hand-derived one-coordinate model
    does. Measured over 2 s at rtol 1e-12: 1.9e-9 and 1.3e-9 rad; the Jacobi integral ½Mα̇² + U (the energy in the
    turning frame, where the drive's work does not count) constant to 1e-9 relative (measured 7e-11, perturbed)."""
    from scipy.optimize import brentq

    omega = 7.0
    U, M, d, rhs = _governor_reduced(omega)
    a_star = brentq(lambda a: d(U, a), 0.05, 1.5, xtol=1e-15)
    assert abs(a_star - 0.9262290591) < 1e-9
    a0 = a_star + offset
    mb = example.flyball_governor(a0, omega)
    model = mb.model()
    assert (model.k, model.nv) == (41, 36)
    q0, v0 = mb.assemble(rates={"spindle.ωz": omega, "arm1.ωy": 0.0})
    times = np.linspace(0.0, 2.0, 41)
    # the rows a near-tie keeps decide the dropped rows' drift: 2e-12 from a* to ten digits, 1.5e-8 from a* to full
    # precision (measured) — the accuracy stated is the larger
    traj = gp.simulate(model, q0, v0, 2.0, record=times, rtol=1e-12, atol=1e-12, constraint_tol=1e-7)
    assert traj.success
    i = mb.coordinate_names.index("arm1.x")
    x, y, z = traj.q[:, i], traj.q[:, i + 1], traj.q[:, i + 2]
    j = mb.velocity_names.index("arm1.ẋ")  # the centre's velocity, world axes
    vx, vy, vz = traj.v[:, j], traj.v[:, j + 1], traj.v[:, j + 2]
    r = np.hypot(x, y)
    alpha = np.arctan2(r, 1.0 - z)  # the arm's centre: r = ½ sin α, 1 − z = ½ cos α
    ref = solve_ivp(rhs, (0.0, 2.0), [a0, 0.0], t_eval=times, method="DOP853", rtol=1e-13, atol=1e-13).y[0]
    assert np.abs(alpha - ref).max() <= 1e-8
    assert np.ptp(alpha) > (0.09 if offset else -1.0)  # the perturbed one swings (to the other side of α*)
    rate = 2 * ((x * vx + y * vy) / r * np.cos(alpha) + vz * np.sin(alpha))  # α̇ from the centre's velocity
    jacobi = 0.5 * np.array([M(a) for a in alpha]) * rate**2 + np.array([U(a) for a in alpha])
    assert np.ptp(jacobi) <= 1e-9 * np.abs(jacobi).max()
    wrong = 0.5 * np.array([M(a) for a in alpha]) * rate**2 + np.array([U(a) + 0.01 * a for a in alpha])
    assert offset == 0.0 or np.ptp(wrong) > 1e-5 * np.abs(jacobi).max()  # negative control: another potential


def test_a_joints_rows_read_the_rotation_alone_not_the_quaternions_norm() -> None:
    """An integrator's stage leaves a spatial body's quaternion off unit length (by its error, ~1e-7 on Bricard's
    default run): the joints' rows must not see it, or the dropped rows' residuals stop following the kept rows' and
    the compiled step hands ~7 evaluations a step to the Python step (Bricard 10 s: 4.7 → 1.3 s). The rows at a
    state with every quaternion scaled by 1.001 are the rows at the state itself; scaled, the unnormalized rotation
    would move them by ~1e-3 (the negative control)."""
    from gausspp.model.mechanism import quaternion_to_matrix

    mb = example.bricard()
    model = mb.model()
    q0, v0 = mb.assemble()
    scaled = q0.copy()
    for i, name in enumerate(mb.coordinate_names):
        if name.split(".")[1] in ("qw", "qx", "qy", "qz"):
            scaled[i] *= 1.001
    lam = np.zeros(model.n_lam)
    g0, g1 = model.evaluate_data(0.0, q0, v0, lam).g, model.evaluate_data(0.0, scaled, v0, lam).g
    assert np.abs(g1 - g0).max() <= 1e-12
    moved = 0.0
    for start in range(3, scaled.size, 7):  # each body's quaternion
        p = scaled[start : start + 4]
        R_raw, R_unit = (np.array(quaternion_to_matrix(x)) for x in (p, p / np.linalg.norm(p)))
        moved = max(moved, float(np.abs(R_raw - R_unit).max()))
    assert moved > 1e-3
