"""Bad inputs to the model front ends, each answered by a project error naming the argument and the fix (or by the
right value): URDF joint types, sympy parameters keyed by name, friction coefficients and a single contact,
Multibody joints on the ground, on one body and with the other kind of body's pose, the energy of
``Model.step_data``, and every refusal of ``from_mjcf`` in one message."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.errors import InputError, NonFiniteError, UnknownNameError

from .factories import kane_system

needs = {
    name: pytest.mark.skipif(importlib.util.find_spec(module) is None, reason=f"needs {module}")
    for name, module in (("adam", "adam"), ("sympy", "sympy"), ("mujoco", "mujoco"))
}


# -- 1. from_urdf: joint types it does not read ---------------------------------------------------------------
def _urdf(kind: str) -> str:
    """Two links: ``j1`` revolute, ``j2`` of type ``kind``."""
    from gausspp.scenes.underactuated_arm import link

    def joint(name: str, parent: str, child: str, type_: str) -> str:
        return (
            f'<joint name="{name}" type="{type_}"><parent link="{parent}"/><child link="{child}"/>'
            '<origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>'
            '<limit effort="1" velocity="1" lower="-1" upper="1"/></joint>'
        )

    body = link("l1") + link("l2") + joint("j1", "base", "l1", "revolute") + joint("j2", "l1", "l2", kind)
    return f'<robot name="r"><link name="base"/>{body}</robot>'


@needs["adam"]
@pytest.mark.parametrize("kind", ["screw", "planar", "floating"])
@pytest.mark.parametrize("joints", [None, ["j1"]])
def test_from_urdf_names_a_joint_of_a_type_it_does_not_read(tmp_path: Path, kind: str, joints: list | None) -> None:
    path = tmp_path / f"{kind}.urdf"
    path.write_text(_urdf(kind))
    with pytest.raises(InputError) as info:
        gp.from_urdf(str(path), joints=joints)
    message = str(info.value)
    assert "'j2'" in message and repr(kind) in message and "revolute" in message and "fixed" in message


# -- 2. from_sympy: parameters keyed by name ------------------------------------------------------------------
def _pendulum_kane() -> tuple:
    return kane_system()


@needs["sympy"]
def test_from_sympy_takes_parameters_keyed_by_symbol_names() -> None:
    kane, (m, l, g) = _pendulum_kane()
    by_name = gp.from_sympy(kane, parameters={"m": 1.5, "l": 0.5, "g": 9.81}).model
    by_symbol = gp.from_sympy(kane, parameters={m: 1.5, l: 0.5, g: 9.81}).model
    q, v = np.array([0.4]), np.array([-0.7])
    assert np.allclose(by_name.step(0.0, q, v).a, by_symbol.step(0.0, q, v).a, rtol=1e-14, atol=0)
    assert by_name.step_data(0.0, q, v).energy == pytest.approx(by_symbol.step_data(0.0, q, v).energy, rel=1e-14)


@needs["sympy"]
def test_from_sympy_names_a_parameter_name_no_symbol_has() -> None:
    kane, _ = _pendulum_kane()
    with pytest.raises(UnknownNameError) as info:
        gp.from_sympy(kane, parameters={"mass": 1.0, "l": 0.5, "g": 9.81})
    assert "'mass'" in str(info.value) and "'m'" in str(info.value)


@needs["sympy"]
def test_from_sympy_refuses_a_name_two_symbols_share() -> None:
    import sympy as sm
    import sympy.physics.mechanics as me

    q, u = me.dynamicsymbols("q u")
    m, twin = sm.Symbol("m"), sm.Symbol("m", positive=True)  # one name, two symbols
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    kane = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    kane.kanes_equations([me.Particle("p", P, m + twin)], [])
    with pytest.raises(InputError) as info:
        gp.from_sympy(kane, parameters={"m": 1.0})
    assert "'m'" in str(info.value) and "symbol itself" in str(info.value)


# -- 3. FrictionContact: coefficients, and one contact where a list is taken ------------------------------------
def _gap(q):
    return q[1]


def _slip(q, v):
    return v[0]


@pytest.mark.parametrize(
    ("kwargs", "name", "error"),
    [
        ({"mu": math.inf}, "mu", NonFiniteError),
        ({"mu": 0.3, "mu_static": math.inf}, "mu_static", NonFiniteError),
        ({"mu": "0.3"}, "mu", InputError),
        ({"mu": 0.3, "mu_static": "0.5"}, "mu_static", InputError),
        ({"mu": True}, "mu", InputError),
    ],
)
def test_friction_contact_refuses_a_coefficient_that_is_no_finite_number(kwargs: dict, name: str, error: type) -> None:
    with pytest.raises(error) as info:
        gp.FrictionContact(_gap, _slip, **kwargs)
    assert f": {name} must be a number, finite" in str(info.value)


def _sliding_point() -> gp.MassMatrix:
    return gp.MassMatrix(2, A=lambda q, t: ca.SX.eye(2), f=lambda q, v, t: ca.vertcat(0.0, -9.81))


def test_simulate_friction_takes_one_contact_as_a_list_of_one() -> None:
    mech, contact = _sliding_point(), gp.FrictionContact(_gap, _slip, 0.3)
    one = gp.simulate_friction(mech, contact, [0.0, 0.0], [1.0, 0.0], 0.1)
    listed = gp.simulate_friction(mech, [contact], [0.0, 0.0], [1.0, 0.0], 0.1)
    assert one.status == "success" and np.array_equal(one.q[-1], listed.q[-1])


@pytest.mark.parametrize("contacts", [[], "contact", [1.0], 3])
def test_simulate_friction_names_contacts_that_are_no_contacts(contacts: object) -> None:
    with pytest.raises(InputError, match="simulate_friction: contacts must be a gp.FrictionContact"):
        gp.simulate_friction(_sliding_point(), contacts, [0.0, 0.0], [1.0, 0.0], 0.1)


def test_gauss_qp_step_takes_one_contact_as_a_list_of_one() -> None:
    pytest.importorskip("clarabel")
    from gausspp.friction.kinematics import ContactKinematics

    contact = gp.FrictionContact(_gap, _slip, 0.3)
    state = ContactKinematics(_sliding_point(), [contact])(np.zeros(2), np.array([1.0, 0.0]))
    one = gp.friction.gauss_qp_step(state, contact, [0])
    listed = gp.friction.gauss_qp_step(state, [contact], [0])
    assert one is not None and listed is not None and np.allclose(one[0], listed[0], rtol=0, atol=1e-12)


# -- 4. Multibody: the ground first, a body joined to itself, the other kind's pose ---------------------------
def _planar() -> gp.Multibody:
    mb = gp.Multibody()
    mb.body("a", 1.0, 0.1, (0.5, 0.0))
    return mb


def _spatial() -> gp.Multibody:
    mb = gp.Multibody(gravity=(0.0, 0.0, -9.81))
    mb.body("a", 1.0, (0.1, 0.1, 0.1), (0.5, 0.0, 0.0))
    return mb


@pytest.mark.parametrize(
    ("make", "join"),
    [
        (_planar, lambda mb: mb.revolute("pin", None, (0, 0), "a", (-0.5, 0))),
        (_planar, lambda mb: mb.prismatic("pin", None, (0, 0), "a", (-0.5, 0), axis=(1, 0))),
        (_planar, lambda mb: mb.fixed("pin", None, (0, 0), "a", (-0.5, 0))),
        (_spatial, lambda mb: mb.spherical("pin", None, (0, 0, 0), "a", (-0.5, 0, 0))),
        (_spatial, lambda mb: mb.revolute("pin", None, (0, 0, 0), "a", (-0.5, 0, 0), axis=(0, 0, 1))),
        (_planar, lambda mb: mb.motor("pin", "a", None, lambda t: t)),
        (_planar, lambda mb: mb.on_curve("pin", None, (0, 0), lambda p, t: p[1])),
    ],
)
def test_multibody_names_a_joint_whose_body_is_the_ground(make, join) -> None:
    with pytest.raises(InputError) as info:
        join(make())
    assert "'pin'" in str(info.value) and "ground (None)" in str(info.value)


@pytest.mark.parametrize(
    ("make", "join"),
    [
        (_planar, lambda mb: mb.revolute("self", "a", (0, 0), "a", (-0.5, 0))),
        (_planar, lambda mb: mb.fixed("self", "a", (0, 0), "a", (-0.5, 0))),
        (_spatial, lambda mb: mb.spherical("self", "a", (0, 0, 0), "a", (-0.5, 0, 0))),
        (_planar, lambda mb: mb.motor("self", "a", "a", lambda t: t)),
    ],
)
def test_multibody_refuses_a_body_joined_to_itself(make, join) -> None:
    mb = make()
    with pytest.raises(InputError) as info:
        join(mb)
    assert "'self'" in str(info.value) and "'a'" in str(info.value) and "itself" in str(info.value)
    assert mb.constraints == []


def test_multibody_refuses_the_pose_of_the_other_kind_of_body() -> None:
    with pytest.raises(InputError, match=r"'b': orientation= is not read for a planar body.*give angle="):
        _planar().body("b", 1.0, 0.1, (0.0, 0.0), orientation=(0.0, 1.0, 0.0, 0.0))
    with pytest.raises(InputError, match=r"'b': angle= is not read for a spatial body.*give orientation="):
        _spatial().body("b", 1.0, (0.1, 0.1, 0.1), (0.0, 0.0, 0.0), angle=0.5)


# -- 5. Model.step_data: the energy --------------------------------------------------------------------------
def test_step_data_gives_the_mechanisms_energy() -> None:
    model = gp.scenes.get("pendulum").model
    mech = model.mechanism
    q, v, t = np.array([0.6, -0.8, 0.3]), np.array([0.8, 0.6, 0.1]), 0.3
    expected = float(ca.Function("E", [mech.q, mech.v, mech.t], [mech.energy])(q, v, t))
    assert expected != 0.0
    assert model.step_data(t, q, v).energy == pytest.approx(expected, rel=1e-14)


def test_step_data_energy_is_nan_without_one() -> None:
    free = gp.MassMatrix(1, A=lambda q, t: ca.SX.eye(1), f=lambda q, v, t: ca.SX.zeros(1))
    assert math.isnan(gp.Model(free, []).step_data(0.0, [0.0], [1.0]).energy)


# -- 6. from_mjcf: every problem in one message ----------------------------------------------------------------
DAMPED_AND_UNMAPPABLE = """
<mujoco model="bad">
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="a" pos="0 0 1">
      <joint name="hinge_a" type="hinge" axis="0 0 1" damping="0.5"/>
      <geom type="sphere" size="0.1"/>
      <body name="b" pos="0.5 0 0">
        <joint name="turn" type="hinge" axis="0 1 0"/>
        <joint name="push" type="slide" axis="1 0 0"/>
        <geom name="drum" type="cylinder" size="0.1 0.1"/>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="rope" frictionloss="0.1"><joint joint="hinge_a" coef="1"/></fixed></tendon>
</mujoco>
"""


@needs["mujoco"]
def test_from_mjcf_lists_every_problem_at_once_and_maps_the_joint_set() -> None:
    """The body with a hinge and a slide (refused in rounds by the old loader) is mapped now; the tendon's
    frictionloss and the cylinder's contact are listed in one message."""
    from gausspp.multibody.mjcf import from_mjcf

    with pytest.raises(InputError) as info:
        from_mjcf(DAMPED_AND_UNMAPPABLE)
    message = str(info.value)
    assert "'rope'" in message and "frictionloss" in message and "'drum'" in message and "cylinder" in message
    free = DAMPED_AND_UNMAPPABLE.replace(' frictionloss="0.1"', "")
    assert from_mjcf(free, contacts="ignore").model.nv == 3
