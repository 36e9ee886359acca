"""Reference problems (docs/theory.md §6): ``get(name, **params)`` builds one, ``names()`` lists them.

Each scene is a module with a ``build(**params) -> Scene`` function, imported only when asked
for: each scene builds only what it needs (no λ state, QP inequality rows or NLP unless asked).
"""

from __future__ import annotations

import importlib
import inspect
import sys
from collections.abc import Callable
from typing import Any

from ..errors import InputError, UnknownNameError
from .scene import Scene, check_parameters
from .scene import parameters as _parameters

#: scene name → module in this package
_MODULES: dict[str, str] = {
    "two-masses": "two_masses",
    "rigid-body-servo": "rigid_body_servo",
    "gyrostat": "gyrostat",
    "gyrostat-extended": "gyrostat_extended",
    "skate": "skate",
    "crane": "crane",
    "mixed-proportional": "mixed",
    "mixed-rate": "mixed",
    "stiff-chain": "stiff_chain",
    "pendulum": "pendulum",
    "andrews": "andrews",
    "block-on-floor": "block_on_floor",
    "bouncing-pendulum": "bouncing_pendulum",
    "saturated-crane": "saturated_crane",
    "two-actuator-servo": "two_actuator_servo",
    "four-bar-redundant": "four_bar",
    "planar-chain": "planar_chain",
    "planar-ladder": "planar_chain",
    "parallelogram": "parallelogram",
    "spatial-parallelogram": "spatial_parallelogram",
    "overhead-crane": "overhead_crane",
    "spring-chain-servo": "spring_chain_servo",
    "ur5-tool-path": "ur5_tool_path",
    "underactuated-arm": "underactuated_arm",
}

#: Scenes whose step is not a square equality system (contacts, bounded or extra actuators, redundant
#: rows): only the general Gauss QP steps them, so studies that compare the direct formula skip them.
#: The parallelogram's rows are redundant at every state with ``third_bar`` and at its collinear positions without;
#: the spatial parallelogram's (revolute joints) at every state.
GENERAL = (
    "block-on-floor",
    "bouncing-pendulum",
    "saturated-crane",
    "two-actuator-servo",
    "four-bar-redundant",
    "parallelogram",
    "spatial-parallelogram",
)

#: Servo scenes realized tangentially: the one-step matrix ``J A⁻¹ Mᵀ`` is singular at every state
#: (the actuators reach the constraint only in a higher derivative, index > 3), so no one-step route steps them:
#: studies and tests that step or simulate every scene skip them; the servo route solves them.
SERVO = ("overhead-crane", "spring-chain-servo")

#: Robots read from URDF: built only with the robots extra (``pip install 'gausspp[robots]'``, a
#: project error without), each stepped by the solver in its ``params["solver"]``; studies and tests that step
#: every scene skip them, their own tests run them.
ROBOT = ("ur5-tool-path", "underactuated-arm")

__all__ = ["GENERAL", "ROBOT", "SERVO", "Scene", "describe", "get", "names", "parameters"]


def names(kind: str = "all") -> list[str]:
    """Names of the scenes: ``"all"``, ``"equality"`` (the direct formula applies), ``"general"`` (the general
    Gauss QP only), ``"servo"`` (index > 3: neither one-step route applies) or ``"robot"`` (URDF robots: the
    robots extra)."""
    if kind == "all":
        return list(_MODULES)
    if kind == "equality":
        return [n for n in _MODULES if n not in GENERAL and n not in SERVO and n not in ROBOT]
    if kind == "general":
        return [n for n in _MODULES if n in GENERAL]
    if kind == "servo":
        return [n for n in _MODULES if n in SERVO]
    if kind == "robot":
        return [n for n in _MODULES if n in ROBOT]
    raise UnknownNameError(f"scene kind {kind!r} is unknown; use 'all', 'equality', 'general', 'servo' or 'robot'")


def _builder(name: str) -> Callable[..., Scene]:
    module = importlib.import_module(f"{__name__}.{_MODULES[name]}")
    builder: Callable[..., Scene] = getattr(module, "build_" + name.replace("-", "_"), None) or module.build
    return builder


def parameters(name: str) -> dict[str, inspect.Parameter]:
    """The parameters of scene ``name``'s builder (name, default, annotation)."""
    if name not in _MODULES:
        raise UnknownNameError(f"scene {name!r} is unknown; available: {names()}")
    return _parameters(_builder(name))


def get(name: str, **params: Any) -> Scene:
    """Build the scene ``name`` with ``params`` (see each scene's ``build`` docstring).

    Every parameter is checked first, in one place (:func:`~gausspp.scenes.scene.check_parameters`):
    an unknown name is an :class:`~gausspp.UnknownNameError`, a value of the wrong type (``F="two"``,
    ``n=2.5``) an :class:`~gausspp.InputError`, NaN or inf a :class:`~gausspp.NonFiniteError`. A module
    lists in ``INFINITE_OK`` the parameters that may be infinite (a bound that is absent).
    """
    if not isinstance(name, str) or name not in _MODULES:
        raise UnknownNameError(f"scene {name!r} is unknown; available: {names()}")
    builder = _builder(name)
    infinite_ok = getattr(sys.modules[builder.__module__], "INFINITE_OK", ())
    params = check_parameters(name, _parameters(builder), params, infinite_ok)
    try:
        return builder(**params)
    except InputError:
        raise
    except (TypeError, ValueError) as exc:  # a parameter of the wrong kind, e.g. n='abc'
        raise InputError(f"scene {name!r}: {exc}") from None


def describe() -> dict[str, str]:
    """One line per scene (the first line of its builder's docstring)."""
    return {name: (_builder(name).__doc__ or "").strip().splitlines()[0] for name in _MODULES}
