"""gausspp — constrained mechanics by Gauss's principle of least constraint, with servo-constraints.

A constraint is kept by a *realization* — ideal, a controlled force (Béghin), a flywheel
(inertial), vakonomic, mixed — and the motion depends on that choice (V. V. Kozlov,
"Principles of dynamics and servo-constraints", 1989). Each step minimizes Gauss's
compulsion as a QP and is cross-checked against the direct multiplier solution.
"""

from __future__ import annotations

from . import qp, realizability, scenes
from .constraints import Constraint, Holonomic
from .errors import (
    GaussppError,
    InputError,
    MissingMultiplierError,
    NonFiniteError,
    NotAffineError,
    NotPositiveDefiniteError,
    QPSolveError,
    RealizabilityError,
    RealizabilityWarning,
    ShapeError,
    UnknownNameError,
)
from .frontends import Lagrangian, MassMatrix, Mechanism, RigidBody
from .model import Model
from .problem import StepProblem, solve
from .realizations import Force, Ideal, Inertial, Mixed, Realization, Vakonomic
from .results import StepResult

__version__ = "0.1.0"

__all__ = [
    "Constraint",
    "Force",
    "GaussppError",
    "Holonomic",
    "Ideal",
    "Inertial",
    "InputError",
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
    "Realization",
    "RealizabilityError",
    "RealizabilityWarning",
    "RigidBody",
    "ShapeError",
    "StepProblem",
    "StepResult",
    "UnknownNameError",
    "Vakonomic",
    "qp",
    "realizability",
    "scenes",
    "solve",
]
