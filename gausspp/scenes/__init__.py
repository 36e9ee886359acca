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
from .categories import CATEGORIES, category
from .categories import category as category_of_name
from .scene import Scene, check_parameters
from .scene import parameters as _parameters

#: The registry, the one place a scene is added: scene name → the module of this package that builds it (its
#: ``build`` or ``build_<name>``), or a builder function ``(**params) -> Scene`` registered from anywhere
#: (``tests/test_extension_points.py`` registers a toy one). Every listing, ``gausspp run NAME`` and
#: ``gausspp scenes NAME`` then find it.
SCENES: dict[str, str | Callable[..., Scene]] = {
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

__all__ = ["SCENES", "Scene", "category", "describe", "get", "names", "parameters"]


def names(category: str = "all") -> list[str]:
    """Names of the scenes: ``"all"``, or those of one category (:mod:`.categories`, computed from the scenes):
    ``"equality"`` (the direct formula applies), ``"general"`` (the general Gauss QP only), ``"servo"`` (index
    > 3: neither one-step solution applies), ``"robot"`` (URDF robots: the robots extra) or ``"unavailable"`` (not
    buildable here: a missing extra)."""
    if category == "all":
        return list(SCENES)
    if category not in CATEGORIES:
        raise UnknownNameError(f"scene category {category!r} is unknown; use 'all' or one of {list(CATEGORIES)}")
    return [n for n in SCENES if category_of_name(n) == category]


def _builder(name: str) -> Callable[..., Scene]:
    where = SCENES[name]
    if callable(where):
        return where
    if not isinstance(where, str):
        raise InputError(f"scene {name!r} is registered as {where!r}: give a module of gausspp.scenes or a builder")
    module = importlib.import_module(f"{__name__}.{where}")
    builder: Callable[..., Scene] = getattr(module, "build_" + name.replace("-", "_"), None) or module.build
    return builder


def parameters(name: str) -> dict[str, inspect.Parameter]:
    """The parameters of scene ``name``'s builder (name, default, annotation)."""
    if name not in SCENES:
        raise UnknownNameError(f"scene {name!r} is unknown; available: {names()}")
    return _parameters(_builder(name))


def get(name: str, **params: Any) -> Scene:
    """Build the scene ``name`` with ``params`` (see each scene's ``build`` docstring).

    Every parameter is checked first, in one place (:func:`~gausspp.scenes.scene.check_parameters`):
    an unknown name is an :class:`~gausspp.UnknownNameError`, a value of the wrong type (``F="two"``,
    ``n=2.5``) an :class:`~gausspp.InputError`, NaN or inf a :class:`~gausspp.NonFiniteError`. A module
    lists in ``INFINITE_OK`` the parameters that may be infinite (a bound that is absent).
    """
    if not isinstance(name, str) or name not in SCENES:
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
    return {name: (_builder(name).__doc__ or "").strip().splitlines()[0] for name in SCENES}
