"""Names of results: a velocity's name and unit from its coordinate's (``"x (m)" → "ẋ (m/s)"``).

Bottom layer (beside :mod:`gausspp.validation`): the scenes name their velocities with it and the figures label
their axes with it, neither importing the other.
"""

from __future__ import annotations

from collections.abc import Sequence

#: A coordinate's unit → its velocity's unit.
_RATE_UNITS = {"(m)": "(m/s)", "(rad)": "(rad/s)", "(1)": "(1/s)"}


def velocity_name(coordinate: str) -> str:
    """The name of the velocity ``q̇`` of a coordinate named ``coordinate`` (name, then unit in parentheses).

    A symbol (one letter, with subscripts) gets a dot over it, ``"x₁ (m)" → "ẋ₁ (m/s)"``; a longer name gets a
    ``d/dt``, ``"elbow (rad)" → "d/dt elbow (rad/s)"``. The unit ``(u)`` becomes ``(u/s)``.
    """
    name, _, unit = coordinate.partition(" (")
    unit = f"({unit}" if unit else ""
    rate = _RATE_UNITS.get(unit, f"{unit[:-1]}/s)" if unit else "")
    symbol = name[:1] + "\u0307" + name[1:] if name[1:].strip("₀₁₂₃₄₅₆₇₈₉") == "" else f"d/dt {name}"
    return f"{symbol} {rate}".strip()


def subscript(i: int) -> str:
    """``i`` in subscript digits: ``12 → "₁₂"``."""
    return str(i).translate(str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉"))


def numbered(symbols: Sequence[str], count: int, start: int = 1) -> tuple[str, ...]:
    """``count`` bodies' coordinates named ``symbols`` (each ``"name (unit)"``), numbered from ``start``:
    ``numbered(["x (m)", "θ (rad)"], 2) == ("x₁ (m)", "θ₁ (rad)", "x₂ (m)", "θ₂ (rad)")``."""
    return tuple(
        f"{name}{subscript(i)} ({unit}"
        for i in range(start, start + count)
        for name, _, unit in (s.partition(" (") for s in symbols)
    )


def velocity_names(coordinates: Sequence[str]) -> tuple[str, ...]:
    """:func:`velocity_name` of each coordinate: the names of ``v = q̇``."""
    return tuple(velocity_name(c) for c in coordinates)
