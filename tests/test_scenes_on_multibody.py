"""Scenes written as bodies and joints (issue 31): ``planar-chain`` and ``planar-ladder`` are built by ``gp.Multibody``;
their motion is the one of the hand-written models they replace, kept here as the reference — each bar's kinetic
energy and weight written out, each pin as two rows of end-point expressions."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import pytest

import gausspp as gp


def _bars(lengths: list[float], m: float, g: float) -> gp.Lagrangian:
    def kinetic(q: Any, v: Any, t: Any) -> Any:
        return sum(0.5 * m * (v[3 * i] ** 2 + v[3 * i + 1] ** 2) + 0.5 * m * lg * lg / 12 * v[3 * i + 2] ** 2
                   for i, lg in enumerate(lengths))  # fmt: skip

    return gp.Lagrangian(
        n=3 * len(lengths), T=kinetic, V=lambda q, t: sum(m * g * q[3 * i + 1] for i in range(len(lengths)))
    )


def _end(q: Any, bar: int, sign: int, length: float) -> Any:
    x, z, th = q[3 * bar], q[3 * bar + 1], q[3 * bar + 2]
    return ca.vertcat(x + sign * 0.5 * length * ca.cos(th), z + sign * 0.5 * length * ca.sin(th))


def _pin(name: str, first: tuple, to: tuple) -> gp.Holonomic:
    if len(to) == 3:
        return gp.Holonomic(lambda q, t: _end(q, *first) - _end(q, *to), name=name)
    return gp.Holonomic(lambda q, t: _end(q, *first) - ca.DM(to), name=name)


def hand_written_chain(N: int, m: float = 1.0, L: float = 1.0, g: float = 9.81) -> gp.Model:
    pins = [_pin("pin-1", (0, -1, L), (0.0, 0.0))] + [
        _pin(f"pin-{i + 1}", (i, -1, L), (i - 1, 1, L)) for i in range(1, N)
    ]
    return gp.Model(_bars([L] * N, m, g), pins)


def hand_written_ladder(N: int, m: float = 1.0, L: float = 1.0, W: float = 1.0, g: float = 9.81) -> gp.Model:
    pins = []
    for i in range(N):
        left, right, rung = 3 * i, 3 * i + 1, 3 * i + 2
        above: list[Any] = [(left - 3, 1, L), (right - 3, 1, L)] if i else [(0.0, 0.0), (W, 0.0)]
        pins += [_pin(f"left-{i + 1}", (left, -1, L), above[0]), _pin(f"right-{i + 1}", (right, -1, L), above[1]),
                 _pin(f"rung-{i + 1} left", (rung, -1, W), (left, 1, L)),
                 _pin(f"rung-{i + 1} right", (rung, 1, W), (right, 1, L))]  # fmt: skip
    return gp.Model(_bars([L, L, W] * N, m, g), pins)


@pytest.mark.parametrize(
    ("name", "params", "reference"),
    [("planar-chain", {"N": 4}, hand_written_chain(4)), ("planar-ladder", {"N": 2}, hand_written_ladder(2))],
)
@pytest.mark.parametrize("method", [{"method": "rk4", "dt": 1e-3}, {}], ids=["rk4", "default"])
def test_a_scene_of_bodies_and_joints_moves_as_its_hand_written_model(name: str, params: dict, reference: gp.Model,
                                                                       method: dict) -> None:  # fmt: skip
    """The same trajectory to 1e-10 relative (measured: equal to the last bit) and the same rows in the same order;
    a ladder whose rung is 1 % longer (the negative control) is told apart."""
    scene = gp.scenes.get(name, **params)
    assert scene.model.k == reference.k and scene.model.route == reference.route
    ours = gp.simulate(scene.model, scene.q0, scene.v0, 1.0, **method)
    theirs = gp.simulate(reference, scene.q0, scene.v0, 1.0, **method)
    assert ours.success and theirs.success and ours.t.size == theirs.t.size
    scale = np.abs(theirs.q).max()
    assert np.abs(ours.q - theirs.q).max() <= 1e-10 * scale and np.abs(ours.v - theirs.v).max() <= 1e-10 * scale
    lam = np.zeros(0)
    J_ours = scene.model.evaluate_data(0.3, ours.q[5], ours.v[5], lam).J
    J_theirs = reference.evaluate_data(0.3, ours.q[5], ours.v[5], lam).J
    np.testing.assert_allclose(J_ours, J_theirs, rtol=0, atol=1e-14)
    if name == "planar-ladder":
        wrong = gp.simulate(hand_written_ladder(2, W=1.01), scene.q0, scene.v0, 1.0, **method, stabilize="project")
        assert np.abs(wrong.q - theirs.q).max() > 1e-4 * scale
