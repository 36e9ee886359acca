"""Rewriting a scene in other units: its parameters' documented units (``gausspp scenes NAME``) read as powers of
kilogram, metre and second, and each value scaled by the factors of a change of units.

Used by the tests of :mod:`gausspp.simulation.scales` (a machine in other units runs with the same status, events
and relative accuracy)."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

#: Base units as powers of (kg, m, s); radians and pure numbers are dimensionless.
BASE = {
    "kg": (1, 0, 0),
    "m": (0, 1, 0),
    "s": (0, 0, 1),
    "N": (1, 1, -2),
    "J": (1, 2, -2),
    "W": (1, 2, -3),
    "rad": (0, 0, 0),
    "1": (0, 0, 0),
    "-": (0, 0, 0),
    "": (0, 0, 0),
}
POWERS = {"²": 2, "³": 3, "⁴": 4, "⁻¹": -1, "⁻²": -2}
_TOKEN = re.compile(r"(kg|rad|[mNsJW1-])((?:⁻?[¹²³⁴])*)")


def dimension(unit: str) -> tuple[int, int, int] | None:
    """``unit`` as powers of (kg, m, s), or ``None`` if it is not a product of the base units."""
    unit = unit.strip()
    if unit in ("-", "1", "", "rad"):
        return (0, 0, 0)
    total = np.zeros(3, int)
    sign = 1
    for part in re.split(r"(/)", unit):
        if part == "/":
            sign = -1
            continue
        for factor in part.split("·"):
            factor = factor.strip()
            if not factor:
                continue
            found = _TOKEN.fullmatch(factor)
            if found is None:
                return None
            power = POWERS.get(found.group(2), 1) if found.group(2) else 1
            total += sign * power * np.array(BASE[found.group(1)])
    return tuple(int(x) for x in total)  # type: ignore[return-value]


def factor(unit: str, mass: float, length: float, time: float) -> float | None:
    """The number a quantity of ``unit`` is multiplied by when every mass's number is multiplied by ``mass``,
    every length's by ``length`` and every time's by ``time`` (lengths ×1e3: metres to millimetres); ``None`` if the
    unit cannot be read."""
    dim = dimension(unit)
    if dim is None:
        return None
    return float(mass ** dim[0] * length ** dim[1] * time ** dim[2])


def rescaled(params: dict[str, Any], units: dict[str, str], mass: float, length: float, time: float) -> dict[str, Any]:
    """``params`` in the new units (non-numeric values kept); a numeric parameter of an unreadable unit raises."""
    out = {}
    for name, value in params.items():
        if isinstance(value, (bool, str)) or value is None:
            out[name] = value
            continue
        f = factor(units[name], mass, length, time)
        if f is None:
            raise ValueError(f"unit {units[name]!r} of {name} cannot be read")
        out[name] = tuple(np.asarray(value, float) * f) if np.ndim(value) else float(value) * f
    return out


def coordinate_factors(labels: tuple[str, ...], mass: float, length: float, time: float) -> np.ndarray:
    """The factor of each coordinate from its label's unit (``"x (m)"``)."""
    out = []
    for label in labels:
        unit = label[label.rfind("(") + 1 : -1] if label.endswith(")") else "-"
        f = factor(unit, mass, length, time)
        if f is None:
            raise ValueError(f"unit of coordinate {label!r} cannot be read")
        out.append(f)
    return np.array(out)
