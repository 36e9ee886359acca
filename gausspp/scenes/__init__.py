"""Reference problems (DESIGN §6): ``get(name, **params)`` builds one, ``names()`` lists them.

Each scene builds only what it needs: no λ state, QP inequality rows or NLP unless asked.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..errors import InputError, UnknownNameError
from . import rigid_body_servo, two_masses
from ._scene import Scene

_BUILDERS: dict[str, Callable[..., Scene]] = {
    "two-masses": two_masses.build,
    "rigid-body-servo": rigid_body_servo.build,
}

__all__ = ["Scene", "describe", "get", "names"]


def names() -> list[str]:
    """Names of every scene."""
    return list(_BUILDERS)


def get(name: str, **params: Any) -> Scene:
    """Build the scene ``name`` with ``params`` (see each scene's ``build`` docstring)."""
    if name not in _BUILDERS:
        raise UnknownNameError(f"scene {name!r} is unknown; available: {names()}")
    try:
        return _BUILDERS[name](**params)
    except TypeError as exc:
        raise InputError(f"scene {name!r}: {exc}") from None


def describe() -> dict[str, str]:
    """One line per scene."""
    return {name: (build.__doc__ or "").strip().splitlines()[0] for name, build in _BUILDERS.items()}
