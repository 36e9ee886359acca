"""gausspp — constrained mechanics by Gauss's principle of least constraint, with servo-constraints.

A constraint is kept by a *realization* — ideal, a controlled force (Béghin), a flywheel
(inertial), vakonomic, mixed — and the motion depends on that choice (V. V. Kozlov,
"Principles of dynamics and servo-constraints", 1989). Each step minimizes Gauss's
compulsion as a QP and is cross-checked against the direct multiplier solution.
"""

import sys

from . import friction, plot, scenes, servo
from .errors import (
    BackendUnavailableError,
    DriftError,
    DriftWarning,
    FrozenModelError,
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
    PainleveError,
    QPSolveError,
    RealizabilityError,
    RealizabilityWarning,
    ShapeError,
    SweepLogWarning,
    SweepWarning,
    SymbolicError,
    UnknownNameError,
)
from .friction import FrictionContact, FrictionRun, simulate_friction
from .model.constraints import Constraint, Holonomic, Unilateral
from .model.from_sympy import SympyModel, from_sympy
from .model.mechanism import Lagrangian, MassMatrix, Mechanism, RigidBody
from .model.model import Model
from .model.realizations import Force, Ideal, Inertial, Mixed, Realization, Vakonomic
from .model.urdf import frame_acceleration_bias, frame_jacobian, frame_position, frame_rotation, from_urdf
from .multibody import Multibody
from .multibody.mjcf import MJCFMachine, from_mjcf
from .servo import ServoDiagnosis, ServoTrajectory, replay, servo_diagnosis, simulate_servo
from .simulation import methods
from .simulation.drift import Baumgarte
from .simulation.linearize import Linearization, linearize
from .simulation.simulate import simulate
from .simulation.trajectory import Trajectory, load_trajectory
from .step import qp, realizability
from .step.problem import StepProblem, solve
from .step.results import StepResult
from .studies import report, sweeps
from .studies.sweeps import sweep
from .verification.crosscheck import CrossCheck, acceleration_qp, crosscheck
from .verification.integral import Verification
from .verification.verify import verify

__version__ = "0.1.0"

# The public modules keep their short import paths (``import gausspp.qp``, ``from gausspp.sweeps import grid``)
# wherever they live in the layout (docs/architecture.md).
for _module in (methods, qp, realizability, report, sweeps):
    sys.modules[f"{__name__}.{_module.__name__.rpartition('.')[2]}"] = _module
del _module, sys  # nothing but the public names, dunders and subpackages in dir(gausspp)

__all__ = [
    "BackendUnavailableError",
    "FrozenModelError",
    "acceleration_qp",
    "Baumgarte",
    "Constraint",
    "CrossCheck",
    "Force",
    "FrictionContact",
    "FrictionRun",
    "from_mjcf",
    "from_sympy",
    "GaussppError",
    "GaussppWarning",
    "DriftError",
    "DriftWarning",
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
    "MJCFMachine",
    "Mixed",
    "Model",
    "Multibody",
    "NonFiniteError",
    "NotAffineError",
    "NotPositiveDefiniteError",
    "PainleveError",
    "QPSolveError",
    "RealizabilityError",
    "RealizabilityWarning",
    "Realization",
    "RigidBody",
    "ServoDiagnosis",
    "ServoTrajectory",
    "ShapeError",
    "StepProblem",
    "StepResult",
    "SweepLogWarning",
    "SweepWarning",
    "SympyModel",
    "SymbolicError",
    "Trajectory",
    "UnknownNameError",
    "Unilateral",
    "Vakonomic",
    "Verification",
    "load_trajectory",
    "methods",
    "friction",
    "plot",
    "replay",
    "servo",
    "servo_diagnosis",
    "simulate_servo",
    "qp",
    "crosscheck",
    "frame_acceleration_bias",
    "frame_jacobian",
    "frame_position",
    "frame_rotation",
    "from_urdf",
    "realizability",
    "report",
    "scenes",
    "simulate",
    "simulate_friction",
    "linearize",
    "Linearization",
    "sweep",
    "sweeps",
    "solve",
    "verify",
]
