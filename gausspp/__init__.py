"""gausspp — constrained mechanics by Gauss's principle of least constraint, with servo-constraints.

A constraint is kept by a *realization* — ideal, a controlled force (Béghin), a flywheel
(inertial), vakonomic, mixed — and the motion depends on that choice (V. V. Kozlov,
"Principles of dynamics and servo-constraints", 1989). Each step minimizes Gauss's
compulsion as a QP and is cross-checked against the direct multiplier solution.

Everything but the errors is loaded on first use (PEP 562): ``import gausspp`` costs little, ``gp.simulate``
loads the simulation layer when it is first touched, ``gp.plot`` matplotlib's figures when a figure is drawn.
"""

from __future__ import annotations

import importlib as _importlib
import importlib.abc as _abc
import importlib.machinery as _machinery
import sys as _sys
from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:  # what the names below are, for type checkers and editors
    from . import friction, plot, scenes, servo
    from .friction import FrictionContact, FrictionRun, JointFriction, simulate_friction
    from .model.constraints import Constraint, Holonomic, Unilateral
    from .model.from_sympy import SympyModel, from_sympy
    from .model.mechanism import Lagrangian, MassMatrix, Mechanism, RigidBody
    from .model.model import Model
    from .model.realizations import Force, Ideal, Inertial, Mixed, Realization, Vakonomic
    from .model.scales import Scales
    from .model.urdf import frame_acceleration_bias, frame_jacobian, frame_position, frame_rotation, from_urdf
    from .model.urdf_contact import frame_contact
    from .multibody import Multibody
    from .multibody.mjcf import MJCFMachine, from_mjcf
    from .servo import ServoDiagnosis, ServoTrajectory, replay, servo_diagnosis, simulate_servo
    from .simulation import methods
    from .simulation.drift import Baumgarte
    from .simulation.linearize import Linearization, linearize
    from .simulation.simulate import simulate
    from .simulation.trajectory import Trajectory, load_trajectory
    from .step import qp, realizability
    from .step.data import StepProblem
    from .step.equality.solve_numbers import solve
    from .step.results import StepResult
    from .studies import report, sweeps
    from .studies.sweeps import sweep
    from .verification.crosscheck import CrossCheck, acceleration_qp, crosscheck
    from .verification.integral import Verification
    from .verification.verify import verify

__version__ = "0.1.0"

#: The public modules by their short names (``gp.qp``, ``import gausspp.sweeps``) and where they live.
_MODULES = {
    "qp": "gausspp.step.qp",
    "realizability": "gausspp.step.realizability",
    "methods": "gausspp.simulation.methods",
    "report": "gausspp.studies.report",
    "sweeps": "gausspp.studies.sweeps",
    "friction": "gausspp.friction",
    "plot": "gausspp.plot",
    "scenes": "gausspp.scenes",
    "servo": "gausspp.servo",
}
#: Every other public name and the module that defines it.
_NAMES = {
    "FrictionContact": "gausspp.friction",
    "FrictionRun": "gausspp.friction",
    "JointFriction": "gausspp.friction",
    "simulate_friction": "gausspp.friction",
    "Constraint": "gausspp.model.constraints",
    "Holonomic": "gausspp.model.constraints",
    "Unilateral": "gausspp.model.constraints",
    "SympyModel": "gausspp.model.from_sympy",
    "from_sympy": "gausspp.model.from_sympy",
    "Lagrangian": "gausspp.model.mechanism",
    "MassMatrix": "gausspp.model.mechanism",
    "Mechanism": "gausspp.model.mechanism",
    "RigidBody": "gausspp.model.mechanism",
    "Model": "gausspp.model.model",
    "Scales": "gausspp.model.scales",
    "Force": "gausspp.model.realizations",
    "Ideal": "gausspp.model.realizations",
    "Inertial": "gausspp.model.realizations",
    "Mixed": "gausspp.model.realizations",
    "Realization": "gausspp.model.realizations",
    "Vakonomic": "gausspp.model.realizations",
    "frame_acceleration_bias": "gausspp.model.urdf",
    "frame_contact": "gausspp.model.urdf_contact",
    "frame_jacobian": "gausspp.model.urdf",
    "frame_position": "gausspp.model.urdf",
    "frame_rotation": "gausspp.model.urdf",
    "from_urdf": "gausspp.model.urdf",
    "Multibody": "gausspp.multibody",
    "MJCFMachine": "gausspp.multibody.mjcf",
    "from_mjcf": "gausspp.multibody.mjcf",
    "ServoDiagnosis": "gausspp.servo",
    "ServoTrajectory": "gausspp.servo",
    "replay": "gausspp.servo",
    "servo_diagnosis": "gausspp.servo",
    "simulate_servo": "gausspp.servo",
    "Baumgarte": "gausspp.simulation.drift",
    "Linearization": "gausspp.simulation.linearize",
    "linearize": "gausspp.simulation.linearize",
    "simulate": "gausspp.simulation.simulate",
    "Trajectory": "gausspp.simulation.trajectory",
    "load_trajectory": "gausspp.simulation.trajectory",
    "StepProblem": "gausspp.step.data",
    "solve": "gausspp.step.equality.solve_numbers",
    "StepResult": "gausspp.step.results",
    "sweep": "gausspp.studies.sweeps",
    "CrossCheck": "gausspp.verification.crosscheck",
    "acceleration_qp": "gausspp.verification.crosscheck",
    "crosscheck": "gausspp.verification.crosscheck",
    "Verification": "gausspp.verification.integral",
    "verify": "gausspp.verification.verify",
}

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
    "JointFriction",
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
    "Scales",
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
    "frame_contact",
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


def __getattr__(name: str) -> Any:
    """A public name, imported on first use and kept (PEP 562)."""
    if name in _MODULES:
        value = _importlib.import_module(_MODULES[name])
    elif name in _NAMES:
        value = getattr(_importlib.import_module(_NAMES[name]), name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*__all__, *(n for n in globals() if n.startswith("__"))})


class _ShortPaths(_abc.MetaPathFinder, _abc.Loader):
    """``import gausspp.qp`` (and the other :data:`_MODULES` that live deeper) gives the module itself."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> Any:
        short = fullname.removeprefix(f"{__name__}.")
        if fullname != f"{__name__}.{short}" or _MODULES.get(short, fullname) == fullname:
            return None
        module = _importlib.import_module(_MODULES[short])
        return _machinery.ModuleSpec(fullname, self, loader_state=(module, module.__spec__))

    def create_module(self, spec: Any) -> Any:
        return spec.loader_state[0]

    def exec_module(self, module: Any) -> None:
        """Nothing to run: the module was imported under its own name. The import system has just given it the
        short name's spec; it gets its own back (its relative imports resolve from where it lives)."""
        module.__spec__ = module.__spec__.loader_state[1]


if not any(isinstance(finder, _ShortPaths) for finder in _sys.meta_path):
    _sys.meta_path.append(_ShortPaths())
