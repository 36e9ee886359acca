"""The two ways a step is solved, named in one place: ``"qp"`` (Gauss's QP, with a QP ``backend``) and
``"direct"`` (the multiplier formula, no backend)."""

from __future__ import annotations

from typing import Any

from ..errors import InputError, UnknownNameError

SOLVERS = ("qp", "direct")


def check_solver(solver: Any, backend: Any = None) -> str:
    """``solver`` if it is one of :data:`SOLVERS` and ``backend`` goes with it, else the error that says why."""
    if solver not in SOLVERS:
        raise UnknownNameError(f"solver={solver!r} is unknown; use {' or '.join(map(repr, SOLVERS))}")
    if solver == "direct" and backend is not None:
        raise InputError(f"backend={backend!r} applies to solver='qp' only")
    return solver
