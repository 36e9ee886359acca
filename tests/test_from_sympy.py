"""gp.from_sympy (issue 20 item 1): sympy.physics.mechanics systems as gausspp models.

Accelerations are compared with sympy's own equations (its mass matrix and forcing, constraint rows included,
solved numerically) at random states on the constraints; trajectories with a hand-written gausspp model.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.model.sympy_expr import FUNCTIONS, to_casadi

sp = pytest.importorskip("sympy")
me = pytest.importorskip("sympy.physics.mechanics")

T = me.dynamicsymbols._t


def _numeric(matrix, subs):
    return np.array(matrix.subs(subs).evalf(30), dtype=float)


def _sympy_acceleration(method, q, u, params):
    """sympy's own answer: its (constraint-augmented) mass matrix and forcing, solved numerically."""
    subs = {**params, **dict(zip(method.q, q, strict=True)), **dict(zip(method.u, u, strict=True))}
    return np.linalg.solve(_numeric(method.mass_matrix, subs), _numeric(method.forcing, subs).ravel())


# -- (a) the rolling disk, nonholonomic (Kane) -----------------------------------------------------
R_, M_, G_ = sp.symbols("r m g")
DISK = {R_: 0.5, M_: 2.0, G_: 9.81}


def _rolling_disk():
    """Yaw q1, lean q2, spin q3, contact point (x, y); speeds: ω of the disk in the lean frame, ẋ, ẏ."""
    q1, q2, q3, x, y = me.dynamicsymbols("q1 q2 q3 x y")
    u1, u2, u3, u4, u5 = me.dynamicsymbols("u1 u2 u3 u4 u5")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    C = me.Point("C")
    C.set_vel(N, u4 * N.x + u5 * N.y)
    centre = C.locatenew("centre", R_ * L.z)
    centre.set_vel(N, C.vel(N) + (R_ * L.z).dt(N))
    w = R.ang_vel_in(N)
    kd = [me.dot(w, L.x) - u1, me.dot(w, L.y) - u2, me.dot(w, L.z) - u3, x.diff(T) - u4, y.diff(T) - u5]
    contact = centre.vel(N) + w.cross(-R_ * L.z)  # the disk's material point at the contact
    velocity = [me.dot(contact, N.x), me.dot(contact, N.y)]
    inertia = me.inertia(L, M_ * R_**2 / 4, M_ * R_**2 / 2, M_ * R_**2 / 4)
    disk = me.RigidBody("disk", centre, R, M_, (inertia, centre))
    kane = me.KanesMethod(
        N,
        q_ind=[q1, q2, q3, x, y],
        u_ind=[u1, u2, u3],
        kd_eqs=kd,
        u_dependent=[u4, u5],
        velocity_constraints=velocity,
        bodies=[disk],
        forcelist=[(centre, -M_ * G_ * N.z)],
    )
    kane.kanes_equations()
    rolling = [me.msubs(v, kane.kindiffdict()) for v in velocity]
    return kane, rolling


def _disk_state(kane, rolling, rng):
    """Random q and independent speeds; ẋ, ẏ from the rolling condition (linear in them)."""
    q = rng.uniform(-1.0, 1.0, 5)
    u = np.r_[rng.uniform(-2.0, 2.0, 3), 0.0, 0.0]
    subs = {**DISK, **dict(zip(kane.q, q, strict=True)), **dict(zip(kane.u[:3], u[:3], strict=True))}
    B, c = sp.linear_eq_to_matrix([e.subs(subs) for e in rolling], kane.u[3:])
    u[3:] = np.linalg.solve(np.array(B, float), np.array(c, float).ravel())
    return q, u


def test_rolling_disk_accelerations_equal_sympys():
    kane, rolling = _rolling_disk()
    imported = gp.from_sympy(kane, parameters=DISK)
    assert imported.coordinates == ("q1", "q2", "q3", "x", "y")
    assert imported.speeds == ("u1", "u2", "u3", "u4", "u5")
    assert [c.name for c in imported.constraints] == ["nonholonomic[0]", "nonholonomic[1]"]
    rng = np.random.default_rng(3)
    for _ in range(4):
        q, u = _disk_state(kane, rolling, rng)
        expected = _sympy_acceleration(kane, q, u, DISK)
        got = imported.model.step(0.0, q, u).a
        assert np.linalg.norm(got - expected) <= 1e-12 * np.linalg.norm(expected)


# -- (b) a double pendulum whose tip slides on a horizontal line (holonomic loop, Lagrange) ----------
L1, L2, H = 1.0, 0.8, 1.2  # tip held at depth H below the pivot
G = 9.81


def _pinned_double_pendulum():
    q1, q2 = me.dynamicsymbols("q1 q2")
    m1, m2, g = sp.symbols("m1 m2 g")
    x1, y1 = L1 * sp.sin(q1), -L1 * sp.cos(q1)
    x2, y2 = x1 + L2 * sp.sin(q2), y1 - L2 * sp.cos(q2)
    kinetic = sum(m / 2 * (x.diff(T) ** 2 + y.diff(T) ** 2) for m, x, y in ((m1, x1, y1), (m2, x2, y2)))
    potential = g * (m1 * y1 + m2 * y2)
    method = me.LagrangesMethod(kinetic - potential, [q1, q2], hol_coneqs=[y2 + H])
    method.form_lagranges_equations()
    return method, {m1: 1.0, m2: 0.7, g: G}


def _hand_written_pendulum():
    def T_(q, v, t):
        vx1, vy1 = L1 * ca.cos(q[0]) * v[0], L1 * ca.sin(q[0]) * v[0]
        vx2, vy2 = vx1 + L2 * ca.cos(q[1]) * v[1], vy1 + L2 * ca.sin(q[1]) * v[1]
        return 0.5 * (vx1**2 + vy1**2) + 0.35 * (vx2**2 + vy2**2)

    def V(q, t):
        y1 = -L1 * ca.cos(q[0])
        return G * (y1 + 0.7 * (y1 - L2 * ca.cos(q[1])))

    mech = gp.Lagrangian(2, T_, V=V)
    return gp.Model(mech, gp.Holonomic(lambda q, t: -L1 * ca.cos(q[0]) - L2 * ca.cos(q[1]) + H, name="tip"))


def _pendulum_state(rng):
    q1 = rng.uniform(0.3, 1.0)
    q2 = -np.arccos((H - L1 * np.cos(q1)) / L2)
    w1 = rng.uniform(-1.0, 1.0)
    w2 = -L1 * np.sin(q1) * w1 / (L2 * np.sin(q2))
    return np.array([q1, q2]), np.array([w1, w2])


def test_pinned_double_pendulum_accelerations_equal_sympys():
    method, params = _pinned_double_pendulum()
    imported = gp.from_sympy(method, parameters=params)
    assert imported.coordinates == ("q1", "q2")
    assert [c.name for c in imported.constraints] == ["holonomic[0]"]
    rng = np.random.default_rng(5)
    for _ in range(4):
        q, v = _pendulum_state(rng)
        subs = {**params, **dict(zip(method.q, q, strict=True)), **dict(zip(method.u, v, strict=True))}
        full = np.linalg.solve(_numeric(method.mass_matrix_full, subs), _numeric(method.forcing_full, subs).ravel())
        expected = full[2:4]  # [q̇, q̈, λ]
        got = imported.model.step(0.0, q, v).a
        assert np.linalg.norm(got - expected) <= 1e-12 * np.linalg.norm(expected)


def test_pinned_double_pendulum_trajectory_equals_the_hand_written_model():
    method, params = _pinned_double_pendulum()
    imported = gp.from_sympy(method, parameters=params).model
    q0, v0 = _pendulum_state(np.random.default_rng(7))
    a = gp.simulate(imported, q0, v0, 0.5, dt=1e-3, method="rk4")
    b = gp.simulate(_hand_written_pendulum(), q0, v0, 0.5, dt=1e-3, method="rk4")
    scale = 1.0 + np.abs(b.q).max()
    assert np.abs(a.q - b.q).max() <= 1e-9 * scale
    assert np.abs(a.v - b.v).max() <= 1e-9 * (1.0 + np.abs(b.v).max())
    names = gp.from_sympy(method, parameters=params).coordinates
    assert a.labels.coordinate == names and b.labels.coordinate != names  # sympy's names reach the results


def test_a_realization_is_chosen_by_constraint_name():
    method, params = _pinned_double_pendulum()
    imported = gp.from_sympy(method, parameters=params, realization={"holonomic[0]": "ideal"})
    assert isinstance(imported.constraints[0].realization, gp.Ideal)
    with pytest.raises(gp.InputError, match="tip"):
        gp.from_sympy(method, parameters=params, realization={"tip": "ideal"})


# -- (c) errors ------------------------------------------------------------------------------------
def _particle_on_a_line(force):
    """Kane's equations of a unit particle on a line ``q`` (speed ``u``) pushed by ``force(t)``."""
    q, u = me.dynamicsymbols("q u")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, u * N.x)
    kane = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(T) - u])
    kane.kanes_equations([me.Particle("p", P, 1)], [(P, force * N.x)])
    return kane


def test_a_derivative_in_kanes_forcing_is_named():
    kane = _particle_on_a_line(me.dynamicsymbols("F").diff(T))
    with pytest.raises(gp.InputError, match=r"Derivative\(F\(t\), t\)"):
        gp.from_sympy(kane, parameters={})


def test_a_missing_parameter_and_a_wrong_source_are_named():
    method, params = _pinned_double_pendulum()
    with pytest.raises(gp.InputError, match="m1"):
        gp.from_sympy(method, parameters={k: v for k, v in params.items() if str(k) != "m1"})
    with pytest.raises(gp.InputError, match="KanesMethod, LagrangesMethod or System"):
        gp.from_sympy(object())


# -- (d) the converter on its own ------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_each_supported_function_matches_numpy(name):
    x = sp.Symbol("x")
    X = ca.SX.sym("x")
    function = getattr(sp, name)
    expr = function(x, sp.Rational(1, 3)) if name in ("atan2", "Min", "Max") else function(x)
    value = 0.37
    got = float(ca.Function("f", [X], [ca.SX(to_casadi(expr, {x: X}))])(value))
    assert got == pytest.approx(float(expr.subs(x, value).evalf(30)), rel=1e-14, abs=1e-15)


def test_sums_products_powers_and_numbers():
    x, y = sp.symbols("x y")
    X, Y = ca.SX.sym("x"), ca.SX.sym("y")
    expr = sp.Rational(3, 7) * x**3 - sp.sqrt(x * y) + y ** sp.Rational(-1, 2) + sp.pi * sp.Float(0.25) + 2**x
    f = ca.Function("f", [X, Y], [ca.SX(to_casadi(expr, {x: X, y: Y}))])
    assert float(f(0.6, 1.7)) == pytest.approx(float(expr.subs({x: 0.6, y: 1.7}).evalf(30)), rel=1e-14)


def test_an_unsupported_function_is_refused_naming_it():
    x = sp.Symbol("x")
    with pytest.raises(gp.InputError, match=r"gamma\(x\)"):
        to_casadi(sp.gamma(x) + x, {x: ca.SX.sym("x")})


def _two_link_points():
    """Two links ``L1``, ``L2`` pinned at ``O`` in the frame ``N``: their angles, speeds and end points."""
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", L1 * (sp.sin(q1) * N.x - sp.cos(q1) * N.y))
    P2 = P1.locatenew("P2", L2 * (sp.sin(q2) * N.x - sp.cos(q2) * N.y))
    P1.set_vel(N, P1.pos_from(O).dt(N).subs({q1.diff(T): u1}))
    P2.set_vel(N, P2.pos_from(O).dt(N).subs({q1.diff(T): u1, q2.diff(T): u2}))
    return q1, q2, u1, u2, N, O, P1, P2


def test_a_system_gives_the_same_accelerations_as_its_lagrange_twin():
    """The pinned pendulum as a ``System`` (sympy's public API only): same accelerations as the Lagrange import."""
    q1, q2, u1, u2, N, O, P1, P2 = _two_link_points()
    system = me.System(N, O)
    system.add_coordinates(q1, q2)
    system.add_speeds(u1, u2)
    system.add_kdes(q1.diff(T) - u1, q2.diff(T) - u2)
    system.add_bodies(me.Particle("p1", P1, 1.0), me.Particle("p2", P2, 0.7))
    system.apply_uniform_gravity(-G * N.y)
    system.add_holonomic_constraints(P2.pos_from(O).dot(N.y) + H)
    imported = gp.from_sympy(system)
    method, params = _pinned_double_pendulum()
    twin = gp.from_sympy(method, parameters=params)
    q, v = _pendulum_state(np.random.default_rng(11))
    assert [c.name for c in imported.constraints] == ["holonomic[0]"]
    expected = twin.model.step(0.0, q, v).a
    assert np.linalg.norm(imported.model.step(0.0, q, v).a - expected) <= 1e-12 * np.linalg.norm(expected)


def test_kanes_velocity_rows_that_differentiate_a_configuration_constraint_are_not_doubled():
    """Kane lists ġ = 0 among its velocity constraints: the import keeps it once, as ``Holonomic``."""
    q1, q2, u1, u2, N, O, P1, P2 = _two_link_points()
    tip = P2.pos_from(O).dot(N.y) + H
    kane = me.KanesMethod(
        N,
        q_ind=[q1],
        u_ind=[u1],
        kd_eqs=[q1.diff(T) - u1, q2.diff(T) - u2],
        q_dependent=[q2],
        configuration_constraints=[tip],
        u_dependent=[u2],
        velocity_constraints=[tip.diff(T).subs({q1.diff(T): u1, q2.diff(T): u2})],
        bodies=[me.Particle("p1", P1, 1.0), me.Particle("p2", P2, 0.7)],
        forcelist=[(P1, -G * 1.0 * N.y), (P2, -G * 0.7 * N.y)],
    )
    kane.kanes_equations()
    imported = gp.from_sympy(kane)
    assert [c.name for c in imported.constraints] == ["holonomic[0]"]
    q, v = _pendulum_state(np.random.default_rng(13))
    expected = _sympy_acceleration(kane, q, v, {})
    assert np.linalg.norm(imported.model.step(0.0, q, v).a - expected) <= 1e-12 * np.linalg.norm(expected)


def test_without_sympy_the_extra_is_named(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "sympy.physics.mechanics", None)
    with pytest.raises(gp.GaussppError, match=r"pip install 'gausspp\[sympy\]'"):
        gp.from_sympy(object())


def test_a_sympy_without_the_attributes_gausspp_reads_is_named() -> None:
    """KanesMethod has no public accessor for its inertial frame and constraints as given; if a sympy release
    drops them, the error says which and what to use instead."""
    kane = _particle_on_a_line(-1)
    assert gp.from_sympy(kane, parameters={}).speeds == ("u",)
    del kane._f_h
    with pytest.raises(gp.InputError, match=r"configuration constraints.*_f_h.*System"):
        gp.from_sympy(kane, parameters={})
