"""``Multibody.ground_contact`` (issue 43): a body's point on the ground, no hand-written gap, through ``gp.simulate``.

Two motions with closed forms, each written from the textbook and not from gausspp: a planar block released at
``v₀`` on the floor on its two bottom corners stops after ``t = v₀/(μg)`` at ``x = v₀²/(2μg)``; a ball thrown
without spin slides, then rolls from ``t = 2v₀/(7μg)`` at ``5v₀/7``. Controls: ``μ`` 1 % off gives another stop.
"""

from __future__ import annotations

import numpy as np
import pytest

import gausspp as gp

G = 9.81


def block(mu: float) -> gp.Multibody:
    mb = gp.Multibody(gravity=(0.0, -G))
    mb.body("block", mass=1.0, inertia=(0.4**2 + 0.2**2) / 12, at=(0.0, 0.1))
    for side, x in (("left", -0.2), ("right", 0.2)):
        mb.ground_contact(side, "block", (x, -0.1), mu=mu)
    return mb


@pytest.mark.parametrize("mu", [0.4, 0.4 * 1.01])
def test_a_block_slides_to_rest_where_coulomb_says(mu: float) -> None:
    v0, mu_true = 3.0, 0.4
    traj = gp.simulate(block(mu).model(), [0.0, 0.1, 0.0], [v0, 0.0, 0.0], 1.0)
    stops = [e for e in traj.events if e["kind"] == "stops slipping"]
    assert traj.success and traj.lane == "friction" and stops
    t_stop, x_end = v0 / (mu_true * G), v0**2 / (2 * mu_true * G)
    off = max(abs(stops[0]["t"] - t_stop) / t_stop, abs(traj.q[-1, 0] - x_end) / x_end)
    print(f"\nμ = {mu}: stops at {stops[0]['t']:.9f} s (Coulomb {t_stop:.9f}), at {traj.q[-1, 0]:.9f} m; off {off:.1e}")
    if mu == mu_true:
        assert off <= 1e-8 and abs(traj.gap).max() <= 1e-9
    else:
        assert off > 1e-3


def test_a_ball_thrown_without_spin_slides_then_rolls() -> None:
    v0, mu, r = 2.0, 0.3, 0.1
    mb = gp.Multibody(gravity=(0.0, 0.0, -G))
    I = 0.4 * r**2
    mb.body("ball", mass=1.0, inertia=(I, I, I), at=(0.0, 0.0, r))
    mb.ground_contact("floor", "ball", radius=r, mu=mu)
    q0 = np.array([0.0, 0.0, r, 1.0, 0.0, 0.0, 0.0])
    traj = gp.simulate(mb.model(), q0, [v0, 0.0, 0.0, 0.0, 0.0, 0.0], 0.5, record=np.linspace(0.0, 0.5, 51))
    rolls = [e for e in traj.events if e["kind"] == "stops slipping"]
    assert traj.success and rolls
    t_roll = 2 * v0 / (7 * mu * G)
    speed = traj.v[-1, 0]
    print(
        f"\nrolls from {rolls[0]['t']:.9f} s (closed form {t_roll:.9f}) at {speed:.9f} m/s (5v₀/7 = {5 * v0 / 7:.9f})"
    )
    assert abs(rolls[0]["t"] - t_roll) <= 1e-8 * t_roll and abs(speed - 5 * v0 / 7) <= 1e-8
    assert np.abs(traj.gap).max() <= 1e-9 and np.abs(traj.v[:, 1]).max() <= 1e-12


def test_bad_ground_contacts_are_named() -> None:
    mb = block(0.4)
    with pytest.raises(gp.InputError, match="a contact 'left' exists already"):
        mb.ground_contact("left", "block", (0.0, 0.0), mu=0.4)
    with pytest.raises(gp.UnknownNameError):
        mb.ground_contact("nose", "nobody", (0.0, 0.0), mu=0.4)
    with pytest.raises(gp.InputError, match="normal must be 2 finite numbers"):
        mb.ground_contact("tilted", "block", (0.0, 0.0), mu=0.4, normal=(0.0, 0.0))
    with pytest.raises(gp.InputError, match="mu must be"):
        mb.ground_contact("slippery", "block", (0.0, 0.0), mu=float("inf"))
