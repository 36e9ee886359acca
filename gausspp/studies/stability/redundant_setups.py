"""The redundant-constraints study's setups: its models and states, tolerances, and how it judges one step.

:mod:`gausspp.studies.stability.redundant` runs the study on them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ... import scenes
from ...errors import GaussppError, RealizabilityError
from ...model.constraints import Constraint, Holonomic
from ...model.mechanism import Lagrangian, MassMatrix
from ...model.model import Model
from ...step import qp
from ...step.results import StepResult
from .common import Solver, fmt, quiet_c_output, realizability_warnings, recorded, relative, solvers

PINS = ("pin-x", "pin-z", "distance")
CIRCLES = ("circle", "circle again")
DRIFTS = (1e-10, 1e-8, 1e-6, 1e-4, 1e-3, 1e-2)
#: Acceleration and multiplier tolerance (relative) for exactly dependent, consistent rows.
EXACT_TOL = 1e-10
#: Off the manifold by δ the answer may differ from the minimal model's at the same state by ``OFF_FLOOR +
#: OFF_PER_DRIFT·δ`` (relative): round-off, plus no more than the drift itself makes uncertain.
OFF_FLOOR, OFF_PER_DRIFT = 1e-12, 2.0
#: Largest relative difference of a simulated trajectory (solver='qp') from the minimal model's.
SIMULATE_TOL = 1e-8
#: Drifts of the scan over the angles.
SCAN_DRIFTS = (1e-8, 2e-8, 3e-8)
#: What solver='direct' adds to its error when the rows are redundant.
QP_ADVICE = "solver='qp' returns the unique acceleration and the least-norm multiplier"


def circle_twice() -> tuple[Model, Model]:
    """A particle on the unit circle under gravity: the minimal model, and the circle written twice."""
    body = Lagrangian(n=2, T=lambda q, v, t: 0.5 * ca.sumsqr(v), V=lambda q, t: 9.81 * q[1])
    circle = Holonomic(lambda q, t: ca.sumsqr(q) - 1.0, name="circle")
    twice = Holonomic(lambda q, t: 2.0 * (ca.sumsqr(q) - 1.0), name="circle again")
    return Model(body, [circle]), Model(body, [circle, twice])


def circle_state() -> tuple[np.ndarray, np.ndarray]:
    """The circle's test state: ``q = (cos 0.3, sin 0.3)``, ``v = 1.5·(−sin 0.3, cos 0.3)`` (on the circle)."""
    return np.array([math.cos(0.3), math.sin(0.3)]), 1.5 * np.array([-math.sin(0.3), math.cos(0.3)])


def pendulum_with_distance() -> tuple[scenes.Scene, Model]:
    """The pendulum scene and the same body with its pins plus the distance constraint they imply."""
    scene = scenes.get("pendulum")
    L = float(scene.params["L"])
    distance = Holonomic(lambda q, t: q[0] ** 2 + q[1] ** 2 - L**2, name="distance")
    return scene, Model(scene.model.mechanism, [*scene.model.constraints, distance])


def pendulum_state(phi: float, omega: float, stretch: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``q = (cos φ·(1 + stretch), sin φ, φ)``, ``v = ω·(−sin φ, cos φ, 1)``: on the manifold iff ``stretch = 0``."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * (1.0 + stretch), s, phi]), np.array([-s * omega, c * omega, omega])


def two_masses(constraints: list[Constraint]) -> Model:
    """Two masses ``diag(1, 2)`` on a line, the second pulled by a unit force, with ``constraints``."""
    body = MassMatrix(2, A=lambda q, t: np.diag([1.0, 2.0]), f=lambda q, v, t: ca.vertcat(0.0, 1.0))
    return Model(body, constraints)


def contradicting_models() -> dict[str, tuple[Model, np.ndarray, np.ndarray, float]]:
    """Dependent rows that describe different constraints, each with a state ``(q, v, t)`` to step at.

    ``speeds``: ``v₁ − v₀ = 0`` and ``v₁ − v₀ − t = 0`` (the same row, right-hand sides that disagree at the
    acceleration level everywhere and at the velocity level for ``t ≠ 0``); ``positions``: ``x₀ = 0`` and
    ``x₀ = 0.5`` (no state satisfies both; their velocity and acceleration rows agree).
    """
    speeds = two_masses(
        [
            Constraint(lambda q, v, t: v[1] - v[0], name="equal speeds"),
            Constraint(lambda q, v, t: v[1] - v[0] - t, name="speeds apart"),
        ]
    )
    positions = two_masses(
        [Holonomic(lambda q, t: q[0], name="x at 0"), Holonomic(lambda q, t: q[0] - 0.5, name="x at 0.5")]
    )
    zero = np.zeros(2)
    return {
        "speeds at t = 0": (speeds, zero, zero, 0.0),
        "speeds at t = 0.5": (speeds, zero, np.array([0.0, 0.5]), 0.5),
        "positions at x = 0.25": (positions, np.array([0.25, 0.0]), zero, 0.0),
        "positions at x = 0": (positions, zero, zero, 0.0),
    }


def least_norm_multiplier(model: Model, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The least-norm ``u`` with ``D u = A a − f − r₀`` (numpy's pseudo-inverse, singular values < 1e-10·max cut)."""
    d = model.step_data(0.0, q, v)
    return np.linalg.pinv(d.D, rcond=1e-10) @ (d.A @ a - d.f - d.r0)


def attempt(
    model: Model, q: np.ndarray, v: np.ndarray, solver: str, backend: str | None, t: float = 0.0
) -> tuple[Any, bool]:
    """One step at ``t``: (the result or the exception, whether a RealizabilityWarning came with it)."""
    with recorded() as caught, quiet_c_output():
        try:
            out: StepResult | Exception = model.step(t, q, v, solver=solver, backend=backend)
        except Exception as exc:  # noqa: BLE001 - judged by the caller; a non-project exception is a finding
            out = exc
    return out, bool(realizability_warnings(caught))


def clear(out: Any, names: tuple[str, ...]) -> bool:
    """A RealizabilityError that names every constraint and says they are redundant."""
    return isinstance(out, RealizabilityError) and "redundant" in str(out) and all(repr(n) in str(out) for n in names)


def clear_direct(out: Any, names: tuple[str, ...]) -> bool:
    """The direct formula's error: clear (:func:`clear`), and pointing to solver='qp'."""
    return clear(out, names) and QP_ADVICE in str(out)


def refuses_redundancy(out: Any) -> bool:
    """The direct formula's refusal, whether or not its message names the constraints."""
    return isinstance(out, RealizabilityError) and "redundant" in str(out) and QP_ADVICE in str(out)


def kind(out: Any) -> str:
    return "answer" if isinstance(out, StepResult) else type(out).__name__


@dataclass
class Section:
    """What one part of the study measured, saw and found wrong."""

    figures: dict[str, float] = field(default_factory=dict)
    observed: str = ""
    problems: list[str] = field(default_factory=list)


@dataclass
class Findings:
    """Outcomes every section reports into: wrong answers and exceptions that are not the project's."""

    wrong_answers: list[str] = field(default_factory=list)
    non_project: list[str] = field(default_factory=list)

    def judge(self, out: Any, ref: np.ndarray, tol: float, where: str) -> float | None:
        """An answer's relative error against ``ref`` (recorded as wrong above ``tol``); ``None`` for an error."""
        if isinstance(out, StepResult):
            err = relative(out.a, ref)
            if err > tol:
                self.wrong_answers.append(f"{where}: error {fmt(err)} > {fmt(tol)}, margin {out.margin:.2g}")
            return err
        if not isinstance(out, GaussppError):
            self.non_project.append(f"{where}: {type(out).__name__}: {out}")
        return None


def qp_ways() -> list[Solver]:
    """Every QP backend installed here (the compiled ones and qpsolvers')."""
    return solvers(qp.names())[1:]


def off_tol(drift: float) -> float:
    return OFF_FLOOR + OFF_PER_DRIFT * drift
