"""QP backends behind one registry: every QP form the project solves goes through :func:`get`.

Two families (docs/theory.md §3), each solving both forms of :mod:`.base` (the equality form of
the compiled step, and the general form — bounds, inequalities, least squares — of
:mod:`gausspp.step.general`'s stages):

* ``casadi:<plugin>`` — casadi's ``conic`` plugins; in the compiled step the QP is a node of the
  model's casadi graph (a step is one C call);
* ``qpsolvers:<solver>`` — any solver qpsolvers finds installed, called from Python.

A name means one solver on every path. A bare solver name is resolved once, by :func:`canonical`:
the qpsolvers solver when qpsolvers has it installed (``"daqp"`` → ``"qpsolvers:daqp"``), else the
casadi plugin (``"qrqp"`` → ``"casadi:qrqp"``). An unknown name is an
:class:`~gausspp.errors.UnknownNameError` listing :func:`names`; a known solver that is not
installed here is a :class:`~gausspp.errors.BackendUnavailableError` — never a substitute.

Defaults, one per form, declared here (:func:`default`):

* the compiled step: :data:`DEFAULT`, ``casadi:qrqp`` — the fastest among the round-off-accurate
  backends, agreeing with the direct solution to round-off (``benchmarks/step.py`` prints the figures);
  OSQP, the core dependency, is always available but iterative (slower, accurate only after polishing);
* the general QP: the first installed of :data:`GENERAL_DEFAULTS`, ``casadi:qrqp`` (always there: casadi's own
  active set, round-off accurate), then ``qpsolvers:daqp`` and ``qpsolvers:osqp``. qrqp is the one that sits
  inside the compiled general step (:mod:`gausspp.step.general.compiled`: one C call per step, the QP in the
  graph); the Python step that decides redundancy and diagnoses a failed step solves its stages with the same
  backend. daqp, OSQP and qrqp agree to round-off on ``benchmarks/general_qp.py``'s cases;
* the cross-check's independent reference: the first installed of :data:`REFERENCE_DEFAULTS`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

from ...errors import BackendUnavailableError, InputError, UnknownNameError
from . import qpsolvers_backend
from .base import ALL_FORMS, FORMS, QP, QPAnswer, QPBackend
from .casadi_conic import PLUGINS, CasadiConic, plugin_available
from .qpsolvers_backend import QpsolversBackend

#: Backends accurate to about 1e-7 only (HiGHS' QP): on a nearly singular stage — redundant rows off the
#: constraint manifold — the general QP's optimality check refuses their answer with a QPSolveError that
#: names the exact backends, rather than passing an inaccurate acceleration on.
APPROXIMATE: frozenset[str] = frozenset({"casadi:highs"})
#: The compiled step's default backend.
DEFAULT = "casadi:qrqp"
#: The general QP's default: the first of these installed here.
GENERAL_DEFAULTS = ("casadi:qrqp", "qpsolvers:daqp", "qpsolvers:osqp")
#: The cross-check's reference (:mod:`gausspp.verification.crosscheck`): exact dense active-set codes first,
#: OSQP last; none of them the compiled step's default, so that the reference shares no solver with it.
REFERENCE_DEFAULTS = ("qpsolvers:daqp", "qpsolvers:quadprog", "qpsolvers:osqp")
#: Backends added from outside the two families: ``"family:solver"`` → a function making the backend (a
#: :class:`QPBackend`). One entry here is the whole registration: :func:`get`, :func:`names` and every path that
#: takes a ``backend=`` name then find it (``tests/test_extension_points.py`` registers a toy one).
REGISTERED: dict[str, Callable[[], QPBackend]] = {}
#: Each form's default, in order of preference.
DEFAULTS: dict[str, tuple[str, ...]] = {
    "step": (DEFAULT,),
    "general": GENERAL_DEFAULTS,
    "reference": REFERENCE_DEFAULTS,
}

__all__ = [
    "ALL_FORMS",
    "DEFAULT",
    "DEFAULTS",
    "FORMS",
    "GENERAL_DEFAULTS",
    "REFERENCE_DEFAULTS",
    "QP",
    "CasadiConic",
    "QPAnswer",
    "QPBackend",
    "QpsolversBackend",
    "REGISTERED",
    "canonical",
    "default",
    "get",
    "names",
    "require",
    "short_name",
]


def names() -> list[str]:
    """Every backend name usable on this machine."""
    compiled = [f"casadi:{p}" for p in PLUGINS if plugin_available(p)]
    return compiled + [f"qpsolvers:{s}" for s in qpsolvers_backend.available()] + list(REGISTERED)


def _unknown(name: str) -> UnknownNameError:
    return UnknownNameError(f"QP backend {name!r} is unknown; valid names here: {names()}")


def canonical(name: str) -> str:
    """``"family:solver"`` for ``name``; a bare solver name by the rule of the module docstring."""
    if ":" in name:
        return name
    if name in qpsolvers_backend.available():
        return f"qpsolvers:{name}"
    if name in PLUGINS and plugin_available(name):
        return f"casadi:{name}"
    if name in PLUGINS:  # known to both routes perhaps, installed in neither: say what is missing
        return f"casadi:{name}"
    if name in qpsolvers_backend.known():
        return f"qpsolvers:{name}"
    raise _unknown(name)


@functools.cache
def _make(name: str) -> QPBackend:
    route, _, solver = name.partition(":")
    if route == "casadi" and solver in PLUGINS:
        if not plugin_available(solver):
            raise BackendUnavailableError(
                f"QP backend {name!r}: casadi on this machine cannot load the conic plugin {solver!r}; "
                f"installed backends: {names()}"
            )
        return CasadiConic(solver)
    if route == "qpsolvers" and solver in qpsolvers_backend.known():
        if solver not in qpsolvers_backend.available():
            raise BackendUnavailableError(
                f"QP backend {name!r}: qpsolvers has no solver {solver!r} installed here "
                f"(installed: {qpsolvers_backend.available()}); try `pip install qpsolvers[{solver}]`"
            )
        return QpsolversBackend(solver)
    raise _unknown(name)


def get(name: str | QPBackend | None = None) -> QPBackend:
    """Return the backend for ``name`` (``None`` → :data:`DEFAULT`), or an instance unchanged."""
    if isinstance(name, QPBackend):
        return name
    if name is None:
        name = DEFAULT
    if not isinstance(name, str):
        raise UnknownNameError(f"QP backend must be a name or a QPBackend, got {type(name).__name__}")
    if name in REGISTERED:
        backend = REGISTERED[name]()
        if not isinstance(backend, QPBackend) or backend.name != name:
            raise InputError(f"the QP backend registered as {name!r} must make a QPBackend named {name!r}")
        return backend
    return _make(canonical(name))


def default(form: str = "step") -> str:
    """The default backend's name for ``form`` (a key of :data:`DEFAULTS`): the first of its list installed here.

    The compiled step's :data:`DEFAULT` is returned as declared (an uninstalled one is reported when used).
    """
    if form not in DEFAULTS:
        raise UnknownNameError(f"QP form {form!r} is unknown; use one of {sorted(DEFAULTS)}")
    if form == "step":
        return DEFAULT
    installed = set(names())
    for candidate in DEFAULTS[form]:
        if candidate in installed:
            return candidate
    raise BackendUnavailableError(f"none of {list(DEFAULTS[form])} is installed: `pip install osqp`")


def require(backend: QPBackend, features: frozenset[str] | set[str]) -> QPBackend:
    """``backend`` if it solves QPs with ``features`` (:data:`FORMS`), else an error naming those that do."""
    missing = set(features) - set(backend.forms)
    if missing:
        able = [n for n in names() if set(features) <= set(get(n).forms)]
        raise InputError(
            f"QP backend {backend.name!r} does not solve QPs with {', '.join(sorted(missing))}; "
            f"backends that do: {able}"
        )
    return backend


def short_name(backend: QPBackend) -> str:
    """The shortest name that resolves to ``backend``: the bare solver where the bare name means it."""
    bare = backend.name.partition(":")[2]
    try:
        return bare if bare and canonical(bare) == backend.name else backend.name
    except UnknownNameError:
        return backend.name
