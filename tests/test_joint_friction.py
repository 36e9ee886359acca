"""Dry friction in a joint (``gp.JointFriction``, MuJoCo's ``frictionloss``): a force along the joint's velocity with
a fixed bound — sticking while the force that holds the joint is within it, slipping against the velocity with the
bound's force otherwise — against the closed forms of a block on a line, in both lanes of the friction machinery."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import gausspp as gp

M, BOUND = 2.0, 3.0


def block(push: float) -> gp.MassMatrix:
    """A mass ``M`` on a line, pushed by a constant force."""
    return gp.MassMatrix(n=1, A=lambda q, t: [[M]], f=lambda q, v, t: [push])


def dry() -> gp.JointFriction:
    return gp.JointFriction(lambda q, v: v[0], BOUND, name="slide")


@pytest.mark.parametrize("step", [None, 1e-3], ids=["adaptive", "fixed"])
def test_a_slipping_joint_stops_where_coulomb_says_and_stays(step: float | None) -> None:
    """Launched at 2 m/s against a push of 1 N below the bound: it decelerates at (F − P)/m, stops at
    t* = m v₀/(F − P) = 2 s after x* = v₀t*/2 = 2 m, and sticks there (the push is within the bound)."""
    push, v0 = 1.0, 2.0
    run = gp.simulate_friction(block(push), [dry()], [0.0], [v0], 3.0, step=step)
    t_stop = M * v0 / (BOUND - push)
    assert run.success
    assert [e["kind"] for e in run.events] == ["stops slipping"]
    assert abs(run.events[0]["t"] - t_stop) <= 1e-9 * t_stop
    assert abs(run.q[-1, 0] - v0 * t_stop / 2) <= 1e-9 and abs(run.v[-1, 0]) <= 1e-12
    assert run.modes[0] == ("slide+",) and run.modes[-1] == ("stick",)
    assert np.allclose(run.F[0], -BOUND) and np.allclose(run.F[-1], -push)  # sliding: the bound; sticking: the push


@pytest.mark.parametrize("push", [2.9, 3.1, -3.1])
def test_held_within_its_bound_and_slipping_beyond_it(push: float) -> None:
    run = gp.simulate_friction(block(push), [dry()], [0.0], [0.0], 1.0)
    assert run.success
    if abs(push) <= BOUND:
        assert np.abs(run.v).max() == 0.0 and np.abs(run.F[:, 0] + push).max() <= 1e-12
    else:
        expected = (push - np.sign(push) * BOUND) / M
        assert abs(run.v[-1, 0] - expected) <= 1e-12 * abs(expected) + 1e-15


@pytest.mark.parametrize("bound", [0.0, -1.0, np.inf, np.nan, "3"])
def test_a_bound_that_is_not_a_positive_number_is_refused(bound: object) -> None:
    with pytest.raises(gp.InputError, match="bound"):
        gp.JointFriction(lambda q, v: v[0], bound)  # type: ignore[arg-type]


SLIDER = """
<mujoco>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="block">
      <joint name="x" type="slide" axis="1 0 0" frictionloss="{bound}"/>
      <geom type="sphere" size="0.1" mass="{mass}" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="needs MuJoCo: pip install mujoco")
def test_frictionloss_from_mjcf_is_the_joints_dry_friction() -> None:
    """MuJoCo's ``frictionloss`` read by ``gp.from_mjcf``: a slide launched at 2 m/s stops after m v₀²/(2F) exactly,
    where MuJoCo's soft constraint lets it creep a little further (reported)."""
    import mujoco

    xml = SLIDER.format(bound=BOUND, mass=M)
    machine = gp.from_mjcf(xml)
    assert [repr(c) for c in machine.contacts] == [f"JointFriction(name='x frictionloss', bound={BOUND:g})"]
    run = gp.simulate(machine.model, [0.0], [2.0], 2.0)
    stop = M * 2.0**2 / (2 * BOUND)
    assert run.status == "success" and abs(run.q[-1, 0] - stop) <= 1e-9 and run.v[-1, 0] == 0.0
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    d.qvel[0] = 2.0
    mujoco.mj_step(m, d, round(2.0 / m.opt.timestep))
    print(f"\nstop at {stop:.6f} m; MuJoCo's soft frictionloss at {d.qpos[0]:.6f} m")
