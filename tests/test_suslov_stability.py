"""Suslov's steady rotations by gp.linearize (issue 30, item 3): the eigenvalues ``0`` and ``s bᵀI₂⁻¹b`` of the
closed form (examples/suslov_stability.py), one rotation attracting and one repelling, and a simulated motion
leaving the one and approaching the other at those rates."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes import suslov

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("suslov_stability", ROOT / "examples" / "suslov_stability.py")
assert _spec is not None and _spec.loader is not None
example = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = example
_spec.loader.exec_module(example)


@pytest.mark.parametrize("name", ["ω+", "ω−"])
def test_the_eigenvalues_are_the_closed_forms(name: str) -> None:
    """Measured: 1e-16 relative to the closed form (casadi's exact derivative), the zero eigenvalue ≤ 2e-16; the
    scene module's own formula (suslov.approach_rate, |s| bᵀI₂⁻¹b) agrees."""
    omega = example.steady_rotations()[name]
    lin = example.linearized(omega)
    mu = example.closed_form(omega)
    assert lin.drift <= 1e-14  # steady: ω̇ = 0 there
    zero, rate = sorted(lin.eigenvalues.real, key=abs)
    assert np.abs(lin.eigenvalues.imag).max() <= 1e-12 * abs(mu)
    assert abs(zero) <= 1e-12 * abs(mu) and abs(rate - mu) <= 1e-12 * abs(mu)
    assert abs(abs(mu) - suslov.approach_rate(example.I, example.l, omega)) <= 1e-12 * abs(mu)


def test_one_rotation_attracts_and_the_other_repels() -> None:
    rates = {name: example.closed_form(w) for name, w in example.steady_rotations().items()}
    assert rates["ω+"] < 0 < rates["ω−"] and abs(rates["ω+"] + rates["ω−"]) <= 1e-12 * abs(rates["ω+"])


def test_a_different_body_is_told_apart() -> None:
    """The negative control: the closed form of a body 1e-6 off in one moment differs from gausspp's eigenvalue of
    the true body by far more than the tolerance above."""
    omega = example.steady_rotations()["ω+"]
    lin = example.linearized(omega)
    saved = example.I.copy()
    try:
        example.I[1, 1] += 1e-6
        wrong = example.closed_form(omega)
    finally:
        example.I[:] = saved
    assert abs(min(lin.eigenvalues.real) - wrong) > 1e3 * 1e-12 * abs(wrong)


def test_a_pushed_motion_leaves_one_rotation_and_approaches_the_other_at_the_predicted_rates() -> None:
    """From 1e-4 off the repelling rotation: the distance from it grows like exp(μ− t) and the distance to the
    attracting rotation of the same energy then falls like exp(μ+ t) — slopes fitted on the log within 1 %."""
    rot = example.steady_rotations()
    start = rot["ω−"] + 1e-4 * np.cross(example.l, rot["ω−"])
    traj = gp.simulate(example.model, [1.0, 0.0, 0.0, 0.0], start, 60.0, record=np.linspace(0.0, 60.0, 601))
    away = np.log(np.linalg.norm(traj.v - rot["ω−"], axis=1))
    toward = np.log(np.linalg.norm(traj.v - suslov.steady_rotation(example.I, example.l, start), axis=1))
    early, late = traj.t < 15.0, traj.t > 40.0
    grow = np.polyfit(traj.t[early], away[early], 1)[0]
    fall = np.polyfit(traj.t[late], toward[late], 1)[0]
    assert abs(grow - example.closed_form(rot["ω−"])) <= 1e-2 * abs(grow)
    assert abs(fall - example.closed_form(rot["ω+"])) <= 1e-2 * abs(fall)
