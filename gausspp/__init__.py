"""gausspp — constrained mechanics by Gauss's principle of least constraint, with servo-constraints.

A constraint is kept by a *realization* — ideal, a controlled force (Béghin), a flywheel
(inertial), vakonomic, mixed — and the motion depends on that choice (V. V. Kozlov,
"Principles of dynamics and servo-constraints", 1989). Each step minimizes Gauss's
compulsion as a QP and is cross-checked against the direct multiplier solution.
"""

from __future__ import annotations

from . import methods, plot, qp, realizability, report, scenes, sweeps
from .constraints import Constraint, Holonomic, Unilateral
from .crosscheck import CrossCheck, acceleration_qp, crosscheck
from .drift import Baumgarte
from .errors import (
    GaussppError,
    GaussppWarning,
    InitialDataError,
    InputError,
    IntegrationError,
    LongRunWarning,
    MissingMultiplierError,
    NonFiniteError,
    NotAffineError,
    NotPositiveDefiniteError,
    QPSolveError,
    RealizabilityError,
    RealizabilityWarning,
    ShapeError,
    SweepLogWarning,
    SymbolicError,
    UnknownNameError,
)
from .frontends import Lagrangian, MassMatrix, Mechanism, RigidBody
from .integral import Verification, verify
from .model import Model
from .problem import StepProblem, solve
from .realizations import Force, Ideal, Inertial, Mixed, Realization, Vakonomic
from .results import StepResult
from .simulate import simulate
from .sweeps import sweep
from .trajectory import Trajectory

__version__ = "0.1.0"

__all__ = [
    "acceleration_qp",
    "Baumgarte",
    "Constraint",
    "CrossCheck",
    "Force",
    "GaussppError",
    "GaussppWarning",
    "Holonomic",
    "Ideal",
    "Inertial",
    "InitialDataError",
    "InputError",
    "IntegrationError",
    "LongRunWarning",
    "Lagrangian",
    "MassMatrix",
    "Mechanism",
    "MissingMultiplierError",
    "Mixed",
    "Model",
    "NonFiniteError",
    "NotAffineError",
    "NotPositiveDefiniteError",
    "QPSolveError",
    "RealizabilityError",
    "RealizabilityWarning",
    "Realization",
    "RigidBody",
    "ShapeError",
    "StepProblem",
    "StepResult",
    "SweepLogWarning",
    "SymbolicError",
    "Trajectory",
    "UnknownNameError",
    "Unilateral",
    "Vakonomic",
    "Verification",
    "methods",
    "plot",
    "qp",
    "crosscheck",
    "realizability",
    "report",
    "scenes",
    "simulate",
    "sweep",
    "sweeps",
    "solve",
    "verify",
]
