"""QP backends behind one registry: ``get(name)``, ``names()``, ``DEFAULT``.

Two routes to the same Gauss QP (docs/theory.md §3):

* ``casadi:<plugin>`` — compiled into the model's casadi graph (a step is one C call);
* ``qpsolvers:<solver>`` — any solver qpsolvers finds installed, called from Python.

A bare solver name (``"osqp"``) means the compiled route when casadi ships that plugin.
The default, ``casadi:qrqp``, measured fastest among the round-off-accurate backends on
this hardware (``benchmarks/step.py``: ≈1.5 µs per QP step, agreement with the direct
solution at 1e-15); OSQP, the core dependency, is always available as ``casadi:osqp`` and
``qpsolvers:osqp`` but is an iterative method (≈13 µs and accurate only after polishing).
"""

from __future__ import annotations

import functools

from ...errors import BackendUnavailableError, UnknownNameError
from . import qpsolvers_route
from .base import QPBackend
from .casadi_conic import PLUGINS, CasadiConic, plugin_available
from .qpsolvers_route import QpsolversBackend

DEFAULT = "casadi:qrqp"

__all__ = ["DEFAULT", "CasadiConic", "QPBackend", "QpsolversBackend", "get", "names"]


def names() -> list[str]:
    """Every backend name usable on this machine."""
    compiled = [f"casadi:{p}" for p in PLUGINS if plugin_available(p)]
    return compiled + [f"qpsolvers:{s}" for s in qpsolvers_route.available()]


@functools.cache
def _make(name: str) -> QPBackend:
    route, _, solver = name.partition(":")
    if route == "casadi" and solver in PLUGINS:
        if not plugin_available(solver):
            raise BackendUnavailableError(f"casadi on this machine cannot load the conic plugin {solver!r}")
        return CasadiConic(solver)
    if route == "qpsolvers":
        if solver not in qpsolvers_route.available():
            raise BackendUnavailableError(
                f"qpsolvers has no solver {solver!r} installed here (installed: {qpsolvers_route.available()}); "
                f"try `pip install qpsolvers[{solver}]`"
            )
        return QpsolversBackend(solver)
    raise UnknownNameError(f"QP backend {name!r} is unknown; valid names here: {names()}")


def get(name: str | QPBackend | None = None) -> QPBackend:
    """Return the backend for ``name`` (``None`` → :data:`DEFAULT`), or an instance unchanged."""
    if isinstance(name, QPBackend):
        return name
    if name is None:
        name = DEFAULT
    if not isinstance(name, str):
        raise UnknownNameError(f"QP backend must be a name or a QPBackend, got {type(name).__name__}")
    if ":" not in name:
        if name in PLUGINS:
            name = f"casadi:{name}"
        elif name in qpsolvers_route.available():
            name = f"qpsolvers:{name}"
        else:
            raise UnknownNameError(f"QP backend {name!r} is unknown; valid names here: {names()}")
    return _make(name)
