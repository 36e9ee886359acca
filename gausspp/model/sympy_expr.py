"""sympy expressions → casadi ``SX``: one recursive walk over sympy's expression tree.

The walk knows sums, products, powers, numbers and the elementary functions casadi has; every leaf is
looked up in a mapping from sympy objects (``Symbol``, a dynamic symbol ``q1(t)``, the time ``t``, or a
``Derivative(q1(t), t)`` where the caller defines one) to casadi symbols or numbers. Anything else — a
``Derivative`` the caller did not map, an unknown function of time, a function casadi lacks — is refused
with an :class:`~gausspp.errors.InputError` that quotes the term. sympy is imported by the caller; this
module only walks objects it is given (so ``import gausspp`` never imports sympy).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import casadi as ca

from ..errors import InputError

#: sympy function name → the casadi function of the same meaning.
FUNCTIONS: dict[str, Callable[..., Any]] = {
    "sin": ca.sin,
    "cos": ca.cos,
    "tan": ca.tan,
    "asin": ca.asin,
    "acos": ca.acos,
    "atan": ca.atan,
    "atan2": ca.atan2,
    "sinh": ca.sinh,
    "cosh": ca.cosh,
    "tanh": ca.tanh,
    "exp": ca.exp,
    "log": ca.log,
    "Abs": ca.fabs,
    "sign": ca.sign,
    "floor": ca.floor,
    "ceiling": ca.ceil,
    "Min": ca.fmin,
    "Max": ca.fmax,
}


def to_casadi(expr: Any, leaves: Mapping[Any, Any]) -> Any:
    """Translate one sympy expression to a casadi expression (or a float).

    Parameters
    ----------
    expr : sympy.Basic
        The expression: built from ``Add``, ``Mul``, ``Pow``, numbers (``Integer``, ``Rational``,
        ``Float``, ``pi``, ``E``) and the functions of :data:`FUNCTIONS`; ``sqrt(x)`` is
        ``Pow(x, 1/2)`` in sympy and becomes ``ca.sqrt``.
    leaves : mapping
        sympy leaf (``Symbol``, ``q1(t)``, ``t``, ``Derivative(q1(t), t)``, …) → casadi symbol or number.

    Raises
    ------
    InputError
        For a leaf missing from ``leaves``, a ``Derivative`` not in ``leaves``, or a function casadi lacks;
        the message quotes the term.
    """
    if expr in leaves:
        return leaves[expr]
    if expr.is_Number or expr.is_NumberSymbol:
        return float(expr)
    args = expr.args
    if expr.is_Add:
        return _fold(lambda a, b: a + b, [to_casadi(a, leaves) for a in args])
    if expr.is_Mul:
        return _fold(lambda a, b: a * b, [to_casadi(a, leaves) for a in args])
    if expr.is_Pow:
        return _power(expr, leaves)
    return _leaf_or_function(expr, leaves)


def matrix_to_casadi(matrix: Any, leaves: Mapping[Any, Any]) -> ca.SX:
    """:func:`to_casadi` on each entry of a sympy matrix (or a list of expressions, read as a column)."""
    rows = [list(matrix.row(i)) for i in range(matrix.rows)] if hasattr(matrix, "rows") else [[e] for e in matrix]
    if not rows:
        return ca.SX(0, 1)
    return ca.vertcat(*[ca.horzcat(*[ca.SX(to_casadi(e, leaves)) for e in row]) for row in rows])


def _fold(op: Callable[[Any, Any], Any], terms: list[Any]) -> Any:
    result = terms[0]
    for term in terms[1:]:
        result = op(result, term)
    return result


def _power(expr: Any, leaves: Mapping[Any, Any]) -> Any:
    """``b**e``: ``sqrt`` for ``e = 1/2``, ``1/sqrt`` for ``−1/2``, an integer power exactly, else ``b**e``."""
    base, exponent = expr.args
    b = to_casadi(base, leaves)
    if exponent.is_Rational and exponent.q == 2 and abs(exponent.p) == 1:
        root = ca.sqrt(b)
        return root if exponent.p == 1 else 1 / root
    return b ** to_casadi(exponent, leaves)


def _leaf_or_function(expr: Any, leaves: Mapping[Any, Any]) -> Any:
    """A function of :data:`FUNCTIONS` applied to translated arguments, or an error quoting ``expr``."""
    name = type(expr).__name__
    if expr.is_Derivative:
        raise InputError(
            f"sympy expression: the term {expr} is a Derivative, which gausspp cannot read; write it with the "
            "generalized speeds (e.g. substitute the kinematic equations, kane.kindiffdict(), before forming "
            "the equations)"
        )
    if expr.is_Symbol:
        raise InputError(f"sympy expression: the symbol {expr} has no value; give it one in parameters={{{expr}: ...}}")
    if expr.is_Function and name in FUNCTIONS:
        return FUNCTIONS[name](*[to_casadi(a, leaves) for a in expr.args])
    if expr.is_Function and type(expr.func).__name__ == "UndefinedFunction":
        raise InputError(
            f"sympy expression: the function of time {expr} is neither a coordinate nor a speed of the system; "
            "give it a value in parameters= or make it a coordinate"
        )
    raise InputError(
        f"sympy expression: casadi has no counterpart for {name} in the term {expr}; "
        f"supported functions: {', '.join(sorted(FUNCTIONS))} (and sums, products, powers, numbers)"
    )
