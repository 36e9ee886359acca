"""Rewriting a scene in other units: its parameters' documented units (``gausspp scenes NAME``) read as powers of
kilogram, metre and second, and each value scaled by the factors of a change of units; and a machine of bodies and
joints (``gp.Multibody``) built in other units from the same SI numbers (:func:`multibody_in_units`).

Used by the tests of :mod:`gausspp.model.run_scales` (a machine in other units runs with the same status, events
and relative accuracy)."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

import gausspp as gp

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


def relative_error(q: np.ndarray, reference: np.ndarray, labels: tuple[str, ...]) -> float:
    """The largest error of a coordinate over the run, relative to the largest value of the coordinates of its unit
    (lengths against lengths, angles against angles): the same number in any units."""
    unit = np.array([label[label.rfind("(") :] for label in labels])
    error = 0.0
    for u in set(unit):
        cols = unit == u
        size = np.abs(reference[:, cols]).max(initial=0.0)
        if size > 0:
            error = max(error, float(np.abs(q[:, cols] - reference[:, cols]).max(initial=0.0) / size))
    return error


# --- a robot description in other units ---------------------------------------------------------------------

#: What each URDF attribute carries, as a unit: origins and primitive shapes are lengths, inertias kg·m²; a joint
#: limit's effort and velocity depend on the joint's type (``_joint_units``).
_URDF_UNITS = {
    ("origin", "xyz"): "m",
    ("mass", "value"): "kg",
    ("box", "size"): "m",
    ("cylinder", "radius"): "m",
    ("cylinder", "length"): "m",
    ("sphere", "radius"): "m",
    **{("inertia", key): "kg·m²" for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
}


def _joint_units(kind: str) -> dict[str, str]:
    """The units of a joint's ``<limit>`` and ``<dynamics>`` attributes (angles are pure numbers)."""
    linear = kind == "prismatic"
    return {
        "lower": "m" if linear else "rad",
        "upper": "m" if linear else "rad",
        "effort": "N" if linear else "N·m",
        "velocity": "m/s" if linear else "1/s",
        "damping": "N·s/m" if linear else "N·m·s",
        "friction": "N" if linear else "N·m",
    }


def urdf_in_units(text: str, mass: float, length: float, time: float) -> str:
    """A URDF's text with every number rewritten in the new units (lengths ×``length``, masses ×``mass``, times
    ×``time``): origins, inertials, primitive shapes, joint limits and dynamics; meshes get a ``scale``."""
    import xml.etree.ElementTree as ET

    root = ET.fromstring(text)

    def scaled(value: str, unit: str) -> str:
        f = factor(unit, mass, length, time)
        assert f is not None, unit
        return " ".join(repr(float(x) * f) for x in value.split())

    for element in root.iter():
        for attribute, value in list(element.attrib.items()):
            unit = _URDF_UNITS.get((element.tag, attribute))
            if unit is not None:
                element.set(attribute, scaled(value, unit))
        if element.tag == "mesh":
            old = [float(x) for x in element.get("scale", "1 1 1").split()]
            element.set("scale", " ".join(repr(x * length) for x in old))
    for joint in root.iter("joint"):
        units = _joint_units(joint.get("type", ""))
        for tag in ("limit", "dynamics"):
            for element in joint.iter(tag):
                for attribute, value in list(element.attrib.items()):
                    if attribute in units:
                        element.set(attribute, scaled(value, units[attribute]))
    return ET.tostring(root, encoding="unicode")


# --- a machine of bodies and joints in other units -----------------------------------------------------------

#: The unit of each coordinate and each velocity of a ``gp.Multibody`` body, by its name after the body's.
COORDINATE_UNITS = {**dict.fromkeys(("x", "y", "z"), "m"), **dict.fromkeys(("θ", "qw", "qx", "qy", "qz"), "rad")}
VELOCITY_UNITS = {**dict.fromkeys(("ẋ", "ẏ", "ż"), "m/s"), **dict.fromkeys(("θ̇", "ωx", "ωy", "ωz"), "rad/s")}
#: The joints whose third and fifth arguments are points (m): ``kind(name, a, pa, b, pb, ...)``.
JOINTS = ("revolute", "prismatic", "spherical", "universal", "cylindrical", "fixed")


def multibody_unit(name: str) -> str:
    """The unit of a ``gp.Multibody`` coordinate or velocity from its name: ``"crank1.θ"`` → rad, ``"crank1.θ̇"`` →
    rad/s."""
    axis = name.rsplit(".", 1)[1]
    return COORDINATE_UNITS.get(axis) or VELOCITY_UNITS[axis]


def multibody_factors(names: Any, mass: float, length: float, time: float) -> np.ndarray:
    """The factor of each of a ``gp.Multibody``'s coordinates or velocities from its name's unit."""
    return np.array([factor(multibody_unit(n), mass, length, time) for n in names], float)


def multibody_in_units(mass: float, length: float, time: float) -> type:
    """A ``gp.Multibody`` that takes every argument in SI and builds the machine with masses' numbers multiplied by
    ``mass``, lengths' by ``length`` and times' by ``time``: gravity as m/s², masses as kg, inertias as kg·m², the
    bodies' centres and the joints' points as m, angles, orientations and axes unchanged, a motor's angle law and a
    spin's rate law read at the SI time (the rate as rad/s), and :meth:`assemble`'s time, held coordinates and rates
    by their units (a rate held by a coordinate's name: its unit per second). A machine written for ``gp.Multibody``
    is built in other units by building it with this class instead (:func:`gausspp_in_units`). Loads and curves
    (functions of the state) are refused."""
    base = gp.Multibody

    def scaled(unit: str, value: Any) -> Any:
        f = factor(unit, mass, length, time)
        assert f is not None, unit
        return np.asarray(value, float) * f

    def rate_unit(name: str) -> str:
        axis = name.rsplit(".", 1)[1]
        return VELOCITY_UNITS.get(axis) or f"{COORDINATE_UNITS[axis]}/s"

    def joint(kind: str) -> Any:
        def rewritten(self: Any, name: str, a: str, pa: Any, b: str | None, pb: Any, *args: Any, **kw: Any) -> Any:
            return getattr(base, kind)(self, name, a, scaled("m", pa), b, scaled("m", pb), *args, **kw)

        return rewritten

    class InUnits(base):  # type: ignore[misc, valid-type]
        def __init__(self, gravity: Any = (0.0, -9.81)) -> None:
            super().__init__(scaled("m/s²", gravity))

        def body(self, name: str, mass: float, inertia: Any, at: Any, angle: Any = None, orientation: Any = None,
                 load: Any = None) -> str:  # fmt: skip
            if load is not None:
                raise NotImplementedError("multibody_in_units: a load (a function of the state) is not rewritten")
            return super().body(name, float(scaled("kg", mass)), scaled("kg·m²", inertia), scaled("m", at), angle,
                                orientation)  # fmt: skip

        def on_curve(self, *args: Any, **kwargs: Any) -> None:
            raise NotImplementedError("multibody_in_units: a curve (a function of a point) is not rewritten")

        on_surface = on_curve

        def motor(self, name: str, a: str | None, b: str, law: Any, realization: Any = None) -> None:
            super().motor(name, a, b, lambda t: law(t / time), realization)

        def spin(self, name: str, body: str, axis: Any, law: Any, realization: Any = None) -> None:
            super().spin(name, body, axis, lambda t: law(t / time) / time, realization)

        def assemble(self, t: float = 0.0, fix: Any = None, rates: Any = None, q: Any = None) -> Any:
            fix = {k: float(scaled(multibody_unit(k), v)) for k, v in (fix or {}).items()}
            rates = {k: float(scaled(rate_unit(k), v)) for k, v in (rates or {}).items()}
            q = None if q is None else np.asarray(q, float) * multibody_factors(self.coordinate_names, mass, length, 1)
            return super().assemble(t * time, fix, rates, q)

    for kind in JOINTS:
        setattr(InUnits, kind, joint(kind))
    return InUnits


def gausspp_in_units(mass: float, length: float, time: float) -> Any:
    """The ``gausspp`` module with its ``Multibody`` rewritten (:func:`multibody_in_units`): what an example
    module's ``gp`` is replaced by to build its machines in other units."""
    rewritten = multibody_in_units(mass, length, time)

    class Module:
        Multibody = rewritten

        def __getattr__(self, name: str) -> Any:
            return getattr(gp, name)

    return Module()
