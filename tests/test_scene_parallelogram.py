"""The parallelogram scenes in maximal coordinates (IFToMM A02, the double parallelogram, a ladder of cells): on the
manifold at the start, their sizes and redundancy, the one-DOF reference (energy, the first collinear instant), the
QP step against the one-DOF acceleration (with a negative control), and a short simulation of A02 against it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import gausspp as gp
from gausspp.scenes.parallelogram import collinear_times, maximal_state, one_dof_reference

G = 9.81
#: Variants, and (I, G) of their one-DOF model worked out by hand: a crank turning about its ground pin has moment
#: m l²/3 and its centre at height (l/2) sin θ; a coupler (mass w m, length w l) translates at the tips' speed l θ̇,
#: at height l sin θ. A02: 2 cranks, 1 coupler; double: 3 cranks, a coupler of mass 2; ladder of 3: 4 cranks and
#: 3 couplers, or 7 cranks and 3 couplers of mass 2.
VARIANTS = {
    "A02": ({}, 2 / 3 + 1, G * (2 * 0.5 + 1)),
    "double": ({"third_bar": True}, 3 / 3 + 2, G * (3 * 0.5 + 2)),
    "ladder-3": ({"cells": 3}, 4 / 3 + 3, G * (4 * 0.5 + 3)),
    "double-ladder-3": ({"cells": 3, "third_bar": True}, 7 / 3 + 6, G * (7 * 0.5 + 6)),
}


def scene(name: str) -> gp.scenes.Scene:
    return gp.scenes.get("parallelogram", **VARIANTS[name][0])


def values(s: gp.scenes.Scene, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The pins' residuals ``g``, their rates ``Φ = ġ``, and the energy of the maximal model at ``(q, v)``."""
    d = s.model.evaluate_data(0.0, q, v, np.zeros(0))
    return np.asarray(d.g), np.asarray(d.Phi), float(d.energy)


def mapped(s: gp.scenes.Scene, theta: float, omega: float, alpha: float = 0.0) -> tuple:
    return maximal_state(theta, omega, alpha, s.params["cells"], s.params["third_bar"], s.params["l"])


@pytest.mark.parametrize("name", list(VARIANTS))
def test_starts_on_the_manifold(name: str) -> None:
    s = scene(name)
    g, Phi, _ = values(s, s.q0, s.v0)
    assert np.abs(g).max() < 1e-14 and np.abs(Phi).max() < 1e-14
    bars = s.q0.reshape(-1, 3)
    np.testing.assert_allclose(bars[0], [0.0, 0.5, np.pi / 2], atol=1e-15)  # crank 1 vertical, centre at 0.5
    np.testing.assert_allclose(bars[1], [0.5 * (1 + s.params["third_bar"]), 1.0, 0.0], atol=1e-15)  # coupler 1
    tips = s.v0.reshape(-1, 3)  # every crank turns at -1 rad/s, every coupler moves at 1 m/s along +x
    np.testing.assert_allclose(tips[1], [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(tips[0], [0.5, 0.0, -1.0], atol=1e-15)


def test_sizes_and_redundant_rows() -> None:
    a02 = scene("A02").model
    assert (a02.nq, a02.k) == (9, 8)
    assert a02.row_names[:2] == ["pin ground-crank1[0]", "pin ground-crank1[1]"]
    assert a02.names == ["pin ground-crank1", "pin crank1-coupler1", "pin crank2-coupler1", "pin ground-crank2"]
    for cells in (1, 2, 4):
        for third_bar, (nq, k) in ((False, (6 * cells + 3, 6 * cells + 2)), (True, (9 * cells + 3, 10 * cells + 2))):
            s = gp.scenes.get("parallelogram", cells=cells, third_bar=third_bar)
            assert (s.model.nq, s.model.k) == (nq, k) and len(s.coordinates) == nq
            J = s.model.evaluate_data(0.0, s.q0, s.v0, np.zeros(0)).J
            assert np.linalg.matrix_rank(J) == nq - 1  # one degree of freedom: k - (nq - 1) rows redundant
    assert scene("double").model.k == 12 and scene("double").model.nq == 12  # Grübler: 12 - 12 = 0
    for name, rank in (("A02", 7), ("double", 10)):  # on the ground line one rank more is lost
        s = scene(name)
        q, v, _ = mapped(s, 0.0, -1.0)
        assert np.linalg.matrix_rank(s.model.evaluate_data(0.0, q, v, np.zeros(0)).J) == rank


@pytest.mark.parametrize("name", list(VARIANTS))
def test_the_reference_keeps_the_energy_of_the_maximal_model(name: str) -> None:
    s = scene(name)
    t = np.linspace(0.0, 10.0, 201)
    theta, omega = one_dof_reference(t, **s.params)
    energy = np.array([values(s, *mapped(s, a, b)[:2])[2] for a, b in zip(theta, omega, strict=True)])
    assert np.abs(energy - energy[0]).max() < 1e-11 * abs(energy[0])
    _, inertia, moment = VARIANTS[name]
    np.testing.assert_allclose(energy, 0.5 * inertia * omega**2 + moment * np.sin(theta), rtol=1e-13)
    assert np.sin(theta).min() < -0.9 and np.abs(np.diff(np.sign(np.sin(theta)))).max() == 2  # turns over


def test_the_first_collinear_instant_of_A02() -> None:
    params = scene("A02").params
    t1 = brentq(lambda t: one_dof_reference(t, **params)[0], 0.5, 1.0, xtol=1e-14)
    assert abs(t1 - 0.708) < 1e-3, t1  # the benchmark's number: cranks horizontal at t ≈ 0.708 s
    times = collinear_times(**params)
    assert times.size >= 10 and abs(times[0] - t1) < 1e-9
    theta, omega = one_dof_reference(t1, **params)
    assert omega < -4.9  # through the ground line, turning clockwise: ½ I θ̇² = ½ I + 2 g


@pytest.mark.parametrize("name", list(VARIANTS))
def test_qp_step_is_the_one_dof_acceleration(name: str) -> None:
    s = scene(name)
    _, inertia, moment = VARIANTS[name]
    theta, omega = 0.9, -2.0  # on the manifold, away from the collinear positions
    q, v, a = mapped(s, theta, omega, -moment * np.cos(theta) / inertia)
    g, Phi, _ = values(s, q, v)
    assert np.abs(g).max() < 1e-14 and np.abs(Phi).max() < 1e-14
    step = s.model.step(0.0, q, v, solver="qp")
    np.testing.assert_allclose(step.a, a, atol=1e-10)
    _, _, weightless = mapped(s, theta, omega, 0.0)  # negative control: the crank's θ̈ without gravity
    assert np.abs(step.a - weightless).max() > 1.0


def test_the_map_to_maximal_coordinates_is_its_derivative() -> None:
    s, h = scene("double-ladder-3"), 1e-4
    theta, omega, alpha = 0.4, 1.3, -0.7
    q, v, a = mapped(s, theta, omega, alpha)
    ahead, behind = mapped(s, theta + h, omega)[0], mapped(s, theta - h, omega)[0]
    dq, ddq = (ahead - behind) / (2 * h), (ahead - 2 * q + behind) / h**2
    np.testing.assert_allclose(v, dq * omega, atol=1e-8)
    np.testing.assert_allclose(a, ddq * omega**2 + dq * alpha, atol=1e-6)


@pytest.mark.parametrize("name", ["A02", "double"])
def test_a_short_run_follows_the_reference(name: str) -> None:
    s = scene(name)
    t = np.linspace(0.0, 0.5, 51)  # before the first collinear position
    traj = gp.simulate(s.model, s.q0, s.v0, 0.5, record=t)
    assert traj.success
    theta, omega = one_dof_reference(traj.t, **s.params)
    reference = [mapped(s, a, b) for a, b in zip(theta, omega, strict=True)]
    np.testing.assert_allclose(traj.q, [r[0] for r in reference], rtol=0, atol=1e-8)
    np.testing.assert_allclose(traj.v, [r[1] for r in reference], rtol=0, atol=1e-7)
    assert abs(theta[-1] - np.pi / 2) > 0.5  # it moved


def test_the_drawing_joins_the_bars_at_the_pins() -> None:
    s = scene("double")
    picture = s.drawing(mapped(s, 0.7, 0.0)[0])
    (b0, t0), (left, right), (b1, t1), (b2, t2) = picture["segments"]  # crank 1, coupler 1, cranks 2 and 3
    np.testing.assert_allclose([left, right], [t0, t2], atol=1e-15)
    np.testing.assert_allclose([b0, b1, b2], picture["fixed"], atol=1e-15)
    np.testing.assert_allclose(0.5 * (left + right), t1, atol=1e-15)


@pytest.mark.parametrize(("params", "match"), [({"cells": 0}, "cells"), ({"l": -1.0}, "l must be positive")])
def test_bad_parameters_are_refused(params: dict, match: str) -> None:
    with pytest.raises(gp.InputError, match=match):
        gp.scenes.get("parallelogram", **params)
