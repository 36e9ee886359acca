"""Checks of arguments at the public entry points: one number, one array, one positive setting.

Each raises a project error (:mod:`gausspp.errors`) whose message names the argument and quotes the value,
never the ``TypeError``/``ValueError`` numpy or Python would raise on it later.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import InputError, NonFiniteError, ShapeError


def number(where: str, value: Any, integer: bool = False, infinite_ok: bool = False) -> float | int:
    """``value`` as one finite ``float`` (or ``int``; ``±inf`` too if ``infinite_ok``), else an error whose
    message is ``where``."""
    if isinstance(value, (str, bytes, bool, np.bool_, complex, np.complexfloating)):
        raise InputError(where)
    try:
        shape = np.shape(value)
    except ValueError:  # ragged nested lists
        shape = ("ragged",)
    if shape != ():
        raise ShapeError(f"{where} (one value, not an array of shape {shape})")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(where) from None
    if np.isnan(x) or (np.isinf(x) and not (infinite_ok and not integer)):
        raise NonFiniteError(where)
    if integer:
        if not x.is_integer():
            raise InputError(where)
        return int(x)
    return x


def short(value: Any, limit: int = 60) -> str:
    """``repr(value)`` on one line, cut to ``limit`` characters (for quoting a bad value in a message)."""
    text = " ".join(repr(value).split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


def array(owner: str, name: str, value: Any, finite: bool = True) -> np.ndarray:
    """A vector or matrix argument as a float array (finite unless ``finite=False``), or an error naming its
    ``owner`` (a scene, a class) and the argument."""
    try:
        raw = np.asarray(value)
        if raw.dtype.kind not in "iuf":  # strings, None, complex, ragged lists
            raise TypeError
        arr = raw.astype(float)
    except (TypeError, ValueError):
        raise InputError(f"{owner}: {name} must be real numbers (a vector or a matrix), got {short(value)}") from None
    if finite and not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{owner}: {name} must be finite, got {short(value)}")
    return arr


def positive(name: str, value: Any, *, zero_ok: bool = False, integer: bool = False, hint: str = "") -> Any:
    """A keyword argument that must be one finite number ``> 0`` (``≥ 0`` with ``zero_ok``), e.g. ``dt``, ``rtol``.

    ``hint`` (what the argument is, an example) follows the requirement in the message.
    """
    kind = ("a non-negative " if zero_ok else "a positive ") + ("integer" if integer else "number")
    where = f"{name} must be {kind}{hint}, got {value!r}"
    x = number(where, value, integer=integer)
    if x < 0 or (x == 0 and not zero_ok):
        raise InputError(where)
    return x


def flag(owner: str, name: str, value: Any) -> bool:
    """A boolean keyword: ``True`` or ``False`` only (a string such as ``"no"`` is not taken as true)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{owner}: {name} must be True or False, got {short(value)}")
    return bool(value)


def unit_vector(scene: str, name: str, value: Any) -> np.ndarray:
    """``value`` as a unit 3-vector, or a clear error naming the scene and the parameter."""
    vec = array(scene, name, value).ravel()
    if vec.shape != (3,):
        raise ShapeError(f"{scene}: {name} must have 3 components, got {vec.size}")
    norm = np.linalg.norm(vec)
    if norm == 0:
        raise InputError(f"{scene}: {name} must be a finite nonzero vector, got {vec.tolist()}")
    return vec / norm


def inertia_matrix(scene: str, inertia: Any) -> np.ndarray:
    """A 3-vector of principal moments or a 3×3 tensor, as a 3×3 array (checked by the front end)."""
    arr = array(scene, "inertia", inertia)
    if arr.shape == (3,):
        return np.diag(arr)
    if arr.shape != (3, 3):
        raise ShapeError(f"{scene}: inertia must be 3 principal moments or a 3×3 tensor, got shape {arr.shape}")
    return arr


def record_times(owner: str, record: Any, t0: float, t_end: float) -> np.ndarray:
    """``record`` as a 1-D array of increasing times within ``[t0, t_end]`` (``gp.simulate``, ``simulate_friction``):
    a time outside the run is refused, never dropped."""
    times = array(owner, "record", record)
    if times.ndim != 1 or times.size == 0:
        raise ShapeError(f"{owner}: record must be a 1-D array of times, got shape {times.shape}")
    if times.min() < t0 or times.max() > t_end:
        raise InputError(
            f"{owner}: record times must lie within [t0, t_end] = [{t0:g}, {t_end:g}], got {times.min():g} … "
            f"{times.max():g}"
        )
    back = np.flatnonzero(np.diff(times) <= 0)
    if back.size:
        i = int(back[0])
        raise InputError(
            f"{owner}: record times must increase, got record[{i}] = {times[i]:g} then record[{i + 1}] = "
            f"{times[i + 1]:g}: sort them (np.unique(record) sorts and drops repeats)"
        )
    return times
