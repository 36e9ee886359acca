"""The general Gauss step's data and answer: :class:`GaussProblem` and :class:`GaussSolution`.

The problem and its stages are described in :mod:`gausspp.step.general`.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ...errors import NonFiniteError, ShapeError


@dataclass(frozen=True)
class GaussProblem:
    """One instant of the general problem (see the module docstring).

    Attributes
    ----------
    A : (n, n)         kinetic-energy matrix
    a0 : (n,)          ``A⁻¹(f + r₀)``, the acceleration with ``u = 0``
    D : (n, m)         reaction directions
    J : (k, n)         rows of every constraint
    phi : (k,)         right-hand sides
    role : (k,) str    ``"eq"``, ``"track"`` or ``"ge"`` per row
    lower, upper : (m,) bounds on ``u`` (``±inf`` when free)
    rows : names of the rows, for messages
    t : time, for messages
    """

    A: np.ndarray
    a0: np.ndarray
    D: np.ndarray
    J: np.ndarray
    phi: np.ndarray
    role: Sequence[str]
    lower: np.ndarray
    upper: np.ndarray
    rows: Sequence[str] = ()
    t: float = float("nan")

    def __post_init__(self) -> None:
        n = self.A.shape[0]
        m = self.D.shape[1] if self.D.ndim == 2 else -1
        k = self.J.shape[0] if self.J.ndim == 2 else -1
        expected = {
            "A": (self.A.shape, (n, n)),
            "a0": (self.a0.shape, (n,)),
            "D": (self.D.shape, (n, m)),
            "J": (self.J.shape, (k, n)),
            "phi": (self.phi.shape, (k,)),
            "lower": (self.lower.shape, (m,)),
            "upper": (self.upper.shape, (m,)),
        }
        for name, (got, want) in expected.items():
            if got != want:
                raise ShapeError(f"GaussProblem: {name} has shape {got}, expected {want}")
        if len(self.role) != k or not set(self.role) <= {"eq", "track", "ge"}:
            raise ShapeError(f"GaussProblem: role needs one of 'eq', 'track', 'ge' per row ({k} rows)")
        for name in ("A", "a0", "D", "J", "phi"):
            if not np.isfinite(getattr(self, name)).all():
                raise NonFiniteError(f"GaussProblem: {name} is not finite{at(self.t)}")
        if (self.lower > self.upper).any():
            raise ShapeError(f"GaussProblem: a lower bound exceeds its upper bound{at(self.t)}")


@dataclass(frozen=True)
class GaussSolution:
    """The general step's answer.

    Attributes
    ----------
    a : (n,)              the acceleration
    u : (m,)              the reaction unknowns (least norm when not unique)
    compulsion : float    ``Z = ‖W u‖²``
    residual : (k,)       ``J a − φ`` per row (≥ 0 on contacts, the tracking error on bounded servo rows)
    tracking_error : float  ``(Σᵢ (Jᵢ a − φᵢ)² / (Jᵢ A⁻¹ Jᵢᵀ))^½`` over tracked rows (0 unless saturated)
    at_bound : (m,) bool  reaction components at one of their bounds (finite bounds only)
    stages : list of str  which stages ran (``track``, ``compulsion``, ``least-norm``)
    S_norm : (k, m)       ``J A⁻¹ D`` with rows and columns normalized in ``A⁻¹`` (the realizability cosines)
    redundant_rows : int  how many equality rows were dependent on the others
    kept_rows : the bilateral rows kept (the others dependent on them), as decided
    kept_cols : the reaction unknowns whose columns of ``W = L⁻¹D`` are independent (in order), as decided
    isolated_rank_drop : rows kept on the open piece of the manifold were dropped at this isolated singular position
    kept_sine : the kept rows' smallest sine against the rows kept before them, where they were decided
    """

    a: np.ndarray
    u: np.ndarray
    compulsion: float
    residual: np.ndarray
    tracking_error: float
    at_bound: np.ndarray
    stages: list[str] = field(default_factory=list)
    redundant_rows: int = 0
    S_norm: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    kept_rows: tuple[int, ...] = ()
    kept_cols: tuple[int, ...] = ()
    isolated_rank_drop: bool = False
    kept_sine: float = 1.0

    @classmethod
    def of_fields(cls, fields: dict[str, object]) -> GaussSolution:
        """The solution with every field in ``fields``, already checked, without the frozen dataclass's per-field
        ``__init__`` (the compiled general step's hot path); takes ``fields`` over as its ``__dict__``."""
        self = object.__new__(cls)
        object.__setattr__(self, "__dict__", fields)
        return self


@dataclass(frozen=True)
class RowRoles:
    """The rows of each role in a problem, as read-only masks (and the tracked rows' indices)."""

    eq: np.ndarray
    track: np.ndarray
    ge: np.ndarray
    tracked: np.ndarray


@functools.lru_cache(maxsize=256)
def _row_roles(role: tuple[str, ...]) -> RowRoles:
    roles = np.array(role, dtype=str)
    eq, track, ge = roles == "eq", roles == "track", roles == "ge"
    out = RowRoles(eq, track, ge, np.flatnonzero(track))
    for mask in (out.eq, out.track, out.ge, out.tracked):
        mask.flags.writeable = False
    return out


def row_roles(p: GaussProblem) -> RowRoles:
    """:class:`RowRoles` of ``p`` (the same object for every problem with the same roles)."""
    return _row_roles(tuple(p.role))


def at(t: float) -> str:
    """`` at t=…`` for messages (empty when the time is not known)."""
    return "" if np.isnan(t) else f" at t={t:.6g}"


def row_names(p: GaussProblem) -> list[str]:
    """The rows' names, for messages (``row i`` when none were given)."""
    return list(p.rows) or [f"row {i}" for i in range(p.J.shape[0])]
