"""The energy of models from sympy (issue 30, item 4): ``traj.energy`` and the energy balance work.

References: the closed form ``E = −m g l cos θ₀`` of a pendulum released at rest, and conservation itself.
"""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp

from .factories import kane_pendulum

sm = pytest.importorskip("sympy")
me = pytest.importorskip("sympy.physics.mechanics")

G, THETA0 = 9.81, 1.0


def _kane(damping: float = 0.0) -> gp.SympyModel:
    """A pendulum in its angle (no constraint), gravity as a load; ``damping`` adds a torque −c u."""
    return kane_pendulum(G, damping)


def _lagrange() -> gp.SympyModel:
    """The same pendulum in Cartesian coordinates with a holonomic constraint; gravity in the Lagrangian."""
    x, y = me.dynamicsymbols("x y")
    m, l, g = sm.symbols("m l g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, x.diff() * N.x + y.diff() * N.y)
    bob = me.Particle("p", P, m)
    bob.potential_energy = -m * g * x
    method = me.LagrangesMethod(me.Lagrangian(N, bob), [x, y], hol_coneqs=[x**2 + y**2 - l**2], frame=N)
    return gp.from_sympy(method, parameters={m: 1.0, l: 1.0, g: G})


def _system() -> gp.SympyModel:
    """The Cartesian pendulum as a ``System`` (its fixed point), gravity as a load."""
    x, y, ux, uy = me.dynamicsymbols("x y ux uy")
    m, l, g = sm.symbols("m l g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    system = me.System(N, O)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, ux * N.x + uy * N.y)
    system.q_ind, system.u_ind = [x, y], [ux, uy]
    system.kdes = [x.diff() - ux, y.diff() - uy]
    system.add_bodies(me.Particle("p", P, m))
    system.add_loads((P, m * g * N.x))
    system.add_holonomic_constraints(x**2 + y**2 - l**2)
    return gp.from_sympy(system, parameters={m: 1.0, l: 1.0, g: G})


ANGLE = ([THETA0], [0.0])
CARTESIAN = ([np.cos(THETA0), np.sin(THETA0)], [0.0, 0.0])


@pytest.mark.parametrize(
    ("build", "start"),
    [(_kane, ANGLE), (_lagrange, CARTESIAN), (_system, CARTESIAN)],
    ids=["Kane", "Lagrange", "System"],
)
def test_a_conservative_sympy_model_keeps_its_energy(build, start) -> None:
    """E = T + V from sympy's bodies and loads: at the start the closed form −m g l cos θ₀, then constant to
    ≤ 1e-9 relative at rtol = atol = 1e-11 (measured ≤ 3.3e-11; 2.2e-10 at the default rtol 1e-9)."""
    out = build()
    traj = gp.simulate(out.model, *start, 3.0, rtol=1e-11, atol=1e-11)
    assert traj.success and np.isfinite(traj.energy).all()
    assert traj.energy[0] == pytest.approx(-G * np.cos(THETA0), rel=1e-12)
    assert np.ptp(traj.energy) <= 1e-9 * abs(traj.energy[0])
    assert np.ptp(traj.q[:, 0]) > 0.3  # it swings: the kinetic and potential parts trade a lot


def test_a_damping_torque_is_non_conservative_and_closes_the_balance() -> None:
    """With a damping torque the energy falls (by 2.1 J of its 5.3 J in 3 s) and E − E₀ = W_forces to round-off
    (measured 2e-12)."""
    grid = np.linspace(0.0, 3.0, 61)
    traj = gp.simulate(_kane(damping=0.2).model, *ANGLE, 3.0, rtol=1e-12, atol=1e-12, record=grid)
    assert traj.success and traj.energy[-1] < traj.energy[0] - 0.5
    assert np.abs(traj.energy_balance()).max() <= 1e-9 * abs(traj.energy[0])
    undamped = gp.simulate(_kane().model, *ANGLE, 3.0, rtol=1e-12, atol=1e-12, record=grid)
    assert np.abs(traj.energy - undamped.energy).max() > 0.5  # negative control: the torque does matter


def test_a_point_with_zero_velocity_that_moves_is_no_origin() -> None:
    """A point whose velocity is set to zero but whose position moves (a rolling contact's) is refused as the
    origin of a potential; the truly fixed one is taken."""
    from gausspp.model.sympy_energy import _stays

    x, u = me.dynamicsymbols("x u")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    contact = O.locatenew("C", x * N.x)
    contact.set_vel(N, 0)  # a material point at rest at this instant, its place moving with x
    P = contact.locatenew("P", N.y)
    P.set_vel(N, u * N.x)
    kd = {x.diff(): u}
    assert _stays(P, O, N, kd, me) and not _stays(P, contact, N, kd, me)
