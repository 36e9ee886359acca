"""Turning what user callables return into casadi ``SX`` of a checked shape."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import casadi as ca
import numpy as np

from ..errors import NotAffineError, ShapeError, SymbolicError
from ..validation import array, short

#: What to write instead when a user function cannot run on casadi symbols.
CASADI_HINT = (
    "write it with casadi operations (ca.sin, ca.sqrt, ca.dot, ...; not math.sin or float()) and index only within "
    "its size"
)


def _to_sx(value: Any) -> ca.SX:
    if isinstance(value, (str, bytes)):  # a sequence of itself: would recurse forever below
        raise TypeError(f"a {type(value).__name__} is no casadi expression")
    if isinstance(value, ca.SX):
        return value
    if isinstance(value, ca.MX):
        raise TypeError("MX expressions are not supported; build the expression from the SX symbols passed in")
    if isinstance(value, (ca.DM, int, float, np.floating, np.integer)):
        return ca.SX(value)
    if isinstance(value, np.ndarray) and value.dtype != object:
        if value.ndim > 2 or value.dtype.kind not in "biuf":
            raise TypeError(f"cannot turn a {value.ndim}-d array of {value.dtype} into a casadi expression")
        return ca.SX(ca.DM(np.atleast_1d(value).astype(float)))
    if isinstance(value, (Sequence, np.ndarray)):
        rows = [v for v in value]
        if rows and all(isinstance(r, (Sequence, np.ndarray)) and not isinstance(r, str) for r in rows):
            return ca.vertcat(*[ca.horzcat(*[_to_sx(e) for e in r]) for r in rows])
        return ca.vertcat(*[_to_sx(r) for r in rows]) if rows else ca.SX(0, 1)
    raise TypeError(f"cannot turn a {type(value).__name__} into a casadi expression")


def as_expression(value: Any, shape: tuple[int | None, int | None], what: str) -> ca.SX:
    """Return ``value`` as an SX of ``shape`` (``None`` = any size), or raise :class:`ShapeError`.

    A scalar is accepted where a ``(1, 1)``, ``(1, None)`` or ``(None, 1)`` shape is asked,
    and a column vector of length ``n`` where a row ``(1, n)`` is asked (and vice versa),
    because users write ``[1, 0]`` for both.
    """
    try:
        expr = _to_sx(value)
    except (TypeError, ValueError, NotImplementedError, RuntimeError) as exc:  # casadi raises the last two
        raise SymbolicError(f"{what} returned {short(value)}: {_last_line(exc)}; {CASADI_HINT}") from None
    rows, cols = shape
    if rows == 1 and expr.size2() == 1 and (cols is None or expr.size1() == cols) and expr.size1() != 1:
        expr = expr.T
    elif cols == 1 and expr.size1() == 1 and expr.size2() != 1:
        expr = expr.T
    elif rows is None and cols not in (None, 1) and expr.size2() == 1 and expr.size1() == cols:
        expr = expr.T  # a flat vector where rows of length ``cols`` are asked: one row
    if (rows is not None and expr.size1() != rows) or (cols is not None and expr.size2() != cols):
        want = f"({'any' if rows is None else rows}, {'any' if cols is None else cols})"
        raise ShapeError(f"{what} returned shape {expr.shape}, expected {want}")
    return ca.densify(expr)


def evaluate(fn: Callable[..., Any], args: Sequence[Any], shape: tuple[int | None, int | None], what: str) -> ca.SX:
    """Call a user callable on symbols and check its result's shape."""
    if not callable(fn):
        raise SymbolicError(f"{what} must be a function, got {short(fn)}")
    try:
        value = fn(*args)
    except (TypeError, ValueError, IndexError, AttributeError, RuntimeError) as exc:  # casadi raises RuntimeError
        raise SymbolicError(
            f"{what} could not be evaluated on casadi symbols ({type(exc).__name__}: {_last_line(exc)}); {CASADI_HINT}"
        ) from exc
    expr = as_expression(value, shape, what)
    if _has_nan_constant(expr):
        raise SymbolicError(
            f"{what} holds a NaN constant where a formula was expected: a function of the math module (math.sin, "
            "math.sqrt, ...) or float() was applied to a casadi symbol, which casadi turns into NaN; casadi symbols "
            "need casadi's functions (casadi.sin, casadi.sqrt, ...) or numpy's, which accept them (np.sin)"
        )
    return expr


def _last_line(exc: Exception) -> str:
    """The last non-empty line of an exception's message (casadi's say where in C++ first, then what)."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    return lines[-1] if lines else type(exc).__name__


def _has_nan_constant(expr: ca.SX) -> bool:
    """Whether the expression graph of ``expr`` holds a NaN constant (what ``math.sin(symbol)`` leaves).

    No formula a user means holds NaN (``NaN · 0`` is already simplified away by casadi).
    """
    fn = ca.Function("scan", ca.symvar(expr), [expr])
    return any(
        fn.instruction_id(k) == ca.OP_CONST and np.isnan(fn.instruction_constant(k)) for k in range(fn.n_instructions())
    )


def require_affine_in(expr: ca.SX, v: ca.SX, what: str) -> None:
    """Raise :class:`NotAffineError` unless ``expr`` is affine in ``v``."""
    if ca.depends_on(ca.jacobian(expr, v), v):
        raise NotAffineError(
            f"{what} must be affine in the velocities (its ∂/∂v depends on v); write it as N_v(q, t) v + N_0(q, t)"
        )


def check_constant_matrix(owner: str, name: str, value: Any, shape: tuple[int, int]) -> np.ndarray:
    """A numeric matrix parameter ``name`` of ``owner`` (a class): real, finite, of the given shape."""
    arr = array(owner, name, value)
    if arr.shape != shape:
        raise ShapeError(f"{owner}: {name} has shape {arr.shape}, expected {shape}")
    return arr
