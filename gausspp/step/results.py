"""Result types: small frozen dataclasses of numpy arrays."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, ShapeError

_NO_CONTACT_FORCE = np.zeros(0)
_NO_CONTACT_FORCE.flags.writeable = False  # empty and read-only: every hot-path result may share it
_HOT_DEFAULTS = {"contact_force": _NO_CONTACT_FORCE, "tracking_error": 0.0, "saturated": None}


@dataclass(frozen=True)
class StepResult:
    """Everything one step computes (docs/theory.md §2–3).

    Attributes
    ----------
    t : float
        Time of the step.
    a : (nv,) array
        The acceleration ``q̈`` (for a rigid body, ``ω̇``).
    u : (m,) array
        The reaction unknowns: ``λ`` for ideal and force realizations, ``λ̇`` for those with
        ``λ`` as state.
    reaction : (nv,) array
        ``R = [T] − F = r₀ + D u`` (paper eq. (5)).
    compulsion : float
        Gauss's compulsion ``Z = (A(a − a₀), a − a₀) = uᵀ Dᵀ A⁻¹ D u`` with
        ``a₀ = A⁻¹(F − h + r₀)``, the quantity the step minimizes.
    margin : float
        Realizability margin: the smallest singular value of ``S = J A⁻¹ D`` with rows and
        columns normalized in the metric ``A⁻¹`` (see :mod:`gausspp.realizability`): 1 for one
        ideal constraint, 0 when (12)/(16) fail or the constraint rows are redundant.
    cosines : (k,) array
        All those singular values, largest first (the cosine of the angle between normal and
        reaction direction, for one constraint).
    residual : (k,) array
        ``J a − φ``: how well the acceleration keeps the differentiated constraint.
    constraint_value : (k,) array
        ``Φ(q, v, t)`` at the state: nonzero means the state is off the constraint.
    free_acceleration : (nv,) array
        ``A⁻¹(F − h)``, the motion with the constraint released (eq. (1)).
    solver : str
        ``"direct"`` or the QP backend's name.
    qp_residuals : (float, float) or None
        The QP's own relative primal ``‖S u − rhs‖∞`` and dual ``‖H u + Sᵀ y‖∞`` residuals
        (each divided by the size of its terms).
    contact_force : (n_contact_rows,) array
        Multipliers ``λ ≥ 0`` of the model's unilateral contacts (0 for open ones; empty without contacts).
    tracking_error : float
        How far bounded servos fall short of their constraints (0 unless an actuator saturates;
        see :class:`~gausspp.Force`).
    saturated : (m,) bool array
        Reaction unknowns at one of their bounds (all ``False`` without bounds).
    """

    t: float
    a: np.ndarray
    u: np.ndarray
    reaction: np.ndarray
    compulsion: float
    margin: float
    cosines: np.ndarray
    residual: np.ndarray
    constraint_value: np.ndarray
    free_acceleration: np.ndarray
    solver: str
    qp_residuals: tuple[float, float] | None = None
    contact_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tracking_error: float = 0.0
    saturated: np.ndarray | None = None

    @classmethod
    def of_checked(cls, fields: dict[str, object]) -> StepResult:
        """The result with ``fields`` (every field but ``contact_force``, ``tracking_error`` and ``saturated``,
        which take their defaults), already checked: the hot path of :mod:`gausspp.step.equality.checked_call`. The same
        object as ``StepResult(**fields)``, built without the frozen dataclass's ``__init__`` (a per-field
        ``object.__setattr__``, a large part of a small step's cost). Takes ``fields`` over as the result's
        ``__dict__``."""
        self = object.__new__(cls)  # an alternate constructor: the new object is this method's own
        fields.update(_HOT_DEFAULTS)
        object.__setattr__(self, "__dict__", fields)
        return self

    @classmethod
    def of_fields(cls, fields: dict[str, object]) -> StepResult:
        """The result with every field in ``fields``, already checked (the compiled general step's hot path),
        built as :meth:`of_checked` builds it; takes ``fields`` over as the result's ``__dict__``."""
        self = object.__new__(cls)
        object.__setattr__(self, "__dict__", fields)
        return self

    def disagreement(self, other: StepResult) -> float:
        """Largest relative difference in ``a`` and in ``u`` from another result of the same step.

        Each is measured against the larger of the two results' norms (``a`` also against the
        free acceleration), so a zero answer compared with round-off gives round-off.
        """
        if not isinstance(other, StepResult):
            raise InputError(f"disagreement: compare with another StepResult, got {type(other).__name__}")
        for name in ("a", "u"):
            mine, theirs = np.shape(getattr(self, name)), np.shape(getattr(other, name))
            if mine != theirs:
                raise ShapeError(
                    f"disagreement: the other result's {name} has shape {theirs}, this one's {mine}: it is a step of "
                    "another model — compare two solutions of the same step (e.g. solver='qp' and 'direct')"
                )
        da = _relative(self.a - other.a, self.a, other.a, self.free_acceleration)
        du = _relative(self.u - other.u, self.u, other.u)
        return max(da, du)


def _relative(diff: np.ndarray, *scales: np.ndarray) -> float:
    scale = max(float(np.max(np.abs(s), initial=0.0)) for s in scales)
    size = float(np.max(np.abs(diff), initial=0.0))
    return size / scale if scale > 0 else size


@dataclass(frozen=True)
class ImpactResult:
    """A velocity jump at contacts (:meth:`gausspp.Model.impact`).

    Attributes
    ----------
    t : float
    v_before, v_after : (nv,) arrays
    lam_after : (n_lam,) array
        ``λ`` after the impact (realizations with ``λ`` as state take the impulse ``Δλ``).
    impulse : (n_contact_rows,) array
        Contact impulses ``Λ ≥ 0`` (0 for open contacts).
    closed : array of int
        The contact rows that took part.
    kinetic_energy_before, kinetic_energy_after : float
    """

    t: float
    v_before: np.ndarray
    v_after: np.ndarray
    lam_after: np.ndarray
    impulse: np.ndarray
    closed: np.ndarray
    kinetic_energy_before: float
    kinetic_energy_after: float
