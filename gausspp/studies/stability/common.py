"""The :class:`Case` every study case returns, and the helpers the cases share."""

from __future__ import annotations

import contextlib
import math
import os
import re
import sys
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

import numpy as np

from ...errors import RealizabilityWarning
from ...step import qp

EPS = float(np.finfo(float).eps)

#: The crane used by several cases (as in tests/test_scene_skate_crane.py): trolley mass, payload
#: mass, rope length, gravity, and the name of its servo-constraint.
CRANE_M0, CRANE_M, CRANE_L, CRANE_G = 1.0, 0.5, 1.0, 9.81
CRANE_ROW = "payload follows s(t)"

#: A way to solve a step: (label, solver, backend).
Solver = tuple[str, str, str | None]


@dataclass(frozen=True)
class Case:
    """One stability case and its verdict.

    Attributes
    ----------
    name : str
    what : str
        The situation.
    expected : str
        What is right.
    observed : str
        What the library did, with numbers.
    verdict : bool
        True if the observation matches what is right.
    figures : dict of str to float
        The key numbers (counts and flags as floats).
    problems : tuple of str
        Library problems found (with a minimal reproduction); empty when the verdict is ✓.
    """

    name: str
    what: str
    expected: str
    observed: str
    verdict: bool
    figures: dict[str, float]
    problems: tuple[str, ...] = field(default=())


def solvers(backends: Iterable[str | None]) -> list[Solver]:
    """The direct formula, then the QP with each backend installed here (``None``: the default)."""
    installed = set(qp.names())
    out: list[Solver] = [("direct", "direct", None)]
    out += [(qp.get(b).name, "qp", b) for b in backends if b is None or b in installed]
    return out


@contextlib.contextmanager
def recorded() -> Iterator[list[warnings.WarningMessage]]:
    """Record every warning raised inside (the study provokes RealizabilityWarnings on purpose)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield caught


def realizability_warnings(caught: list[warnings.WarningMessage]) -> list[str]:
    """The messages of the :class:`~gausspp.RealizabilityWarning`\\ s among ``caught``."""
    return [str(w.message) for w in caught if issubclass(w.category, RealizabilityWarning)]


@contextlib.contextmanager
def quiet_c_output() -> Iterator[None]:
    """Silence what C libraries print to file descriptors 1 *and* 2 (OSQP, SUNDIALS).

    ``gausspp.qp.casadi_conic.stdout_silenced`` covers only descriptor 1; OSQP's set-up errors
    go to 2.
    """
    saved: list[tuple[int, int]] = []
    try:
        for stream in (sys.stdout, sys.stderr):
            try:
                fd = stream.fileno()
            except (AttributeError, OSError, ValueError):
                continue
            stream.flush()
            saved.append((fd, os.dup(fd)))
        with open(os.devnull, "w") as null:
            for fd, _ in saved:
                os.dup2(null.fileno(), fd)
            yield
    finally:
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)


def relative(x: np.ndarray, ref: np.ndarray) -> float:
    """``max|x − ref| / max|ref|``."""
    return float(np.max(np.abs(x - ref)) / max(float(np.max(np.abs(ref))), 1e-300))


def times_in(message: str) -> list[float]:
    """Every ``t=…`` in a message, in order (unparsable ones as NaN)."""
    out = []
    for found in re.findall(r"t=([-+0-9.eE]+)", message):
        try:
            out.append(float(found.rstrip(".")))
        except ValueError:
            out.append(math.nan)
    return out


def fmt(x: float) -> str:
    """Two significant digits."""
    return f"{x:.2g}"


__all__ = [
    "CRANE_G",
    "CRANE_L",
    "CRANE_M",
    "CRANE_M0",
    "CRANE_ROW",
    "EPS",
    "Case",
    "Solver",
    "fmt",
    "quiet_c_output",
    "realizability_warnings",
    "recorded",
    "relative",
    "solvers",
    "times_in",
]
