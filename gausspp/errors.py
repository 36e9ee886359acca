"""Project exceptions and warnings.

Every error raised by gausspp derives from :class:`GaussppError`. Errors caused by
what the user passed also derive from :class:`ValueError`, so ``except ValueError``
keeps working for callers who do not know this library. Messages say *what* is
wrong, *where* (time, constraint, parameter) and *how* to fix it.
"""

from __future__ import annotations


class GaussppError(Exception):
    """Root of every gausspp exception."""


class InputError(GaussppError, ValueError):
    """Something the user passed is malformed (shape, type, value)."""


class ShapeError(InputError):
    """An array or a symbolic expression has the wrong shape."""


class SymbolicError(ShapeError):
    """A user function could not be written on casadi symbols.

    It raised on them, returned something that is no expression (a string, ``None``), or applied a
    function of :mod:`math` (or ``float()``) to a symbol, which casadi turns into a NaN constant.
    """


class NonFiniteError(InputError):
    """A NaN or an infinity was passed in, or appeared in the model's output."""


class NotPositiveDefiniteError(InputError):
    """The kinetic-energy matrix ``A`` is not symmetric positive definite."""


class NotAffineError(InputError):
    """A function that must be affine in the velocities is not."""


class MissingMultiplierError(InputError):
    """A realization with λ as state (inertial, vakonomic, mixed) lacks ``lam0``."""


class InitialDataError(InputError):
    """Initial data do not satisfy the constraints."""


class UnknownNameError(InputError):
    """An unknown backend, scene, method or realization name was requested."""


class RealizabilityError(GaussppError):
    """The step matrix ``S = J A⁻¹ D`` is singular: the realization cannot keep the constraint.

    Conditions (12) and (16) of the paper. Attributes give the time, the constraint
    most involved and the margin.
    """

    def __init__(
        self, message: str, *, t: float = float("nan"), constraint: str = "", margin: float = float("nan")
    ) -> None:
        super().__init__(message)
        self.t = t
        self.constraint = constraint
        self.margin = margin


class QPSolveError(GaussppError):
    """A QP backend did not return a solution of the requested accuracy."""


class IntegrationError(GaussppError):
    """The time integrator could not continue (step size underflow, too many steps)."""


class DriftError(IntegrationError):
    """The recorded motion left its constraints, or its energy balance, by more than the run's ``drift_tol`` allows.

    A step that answered at every state can still carry the motion off the manifold: a fixed step too long for
    the motion, or a step across a singular position onto a state the constraints no longer hold. Attributes
    give the first time and the row (``"energy balance"`` when the energy, not a row, is what was left).
    """

    def __init__(
        self, message: str, *, t: float = float("nan"), constraint: str = "", residual: float = float("nan")
    ) -> None:
        super().__init__(message)
        self.t, self.constraint, self.residual = t, constraint, residual


class PainleveError(GaussppError):
    """Painlevé's paradox: a sliding contact whose friction makes the normal problem have no solution or two.

    Attributes give the time, the contact and the critical friction coefficient beyond which it happens.
    """

    def __init__(
        self, message: str, *, t: float = float("nan"), contact: str = "", mu_critical: float = float("nan")
    ) -> None:
        super().__init__(message)
        self.t, self.contact, self.mu_critical = t, contact, mu_critical

    def __reduce__(self):  # type: ignore[no-untyped-def]
        return (_painleve, (self.args[0] if self.args else "", self.t, self.contact, self.mu_critical))


def _painleve(message: str, t: float, contact: str, mu_critical: float) -> PainleveError:
    return PainleveError(message, t=t, contact=contact, mu_critical=mu_critical)


class FrozenModelError(GaussppError, AttributeError):
    """An attribute of a :class:`~gausspp.Model` was set: a model does not change once built."""


class BackendUnavailableError(GaussppError, ImportError):
    """A known QP backend is not installed on this machine."""


class GaussppWarning(UserWarning):
    """Root of every gausspp warning."""


class RealizabilityWarning(GaussppWarning):
    """The realizability margin is small: the reaction is large and ill-determined."""


class DriftWarning(GaussppWarning):
    """A run reached ``t_end``, but its residuals or its energy balance left the run's ``constraint_tol``
    (status ``"drifted"``)."""


class LongRunWarning(GaussppWarning):
    """A run asks for very many steps (an estimate is given up front, before the wait)."""


class SweepWarning(GaussppWarning):
    """A sweep finished, but none of its tasks succeeded."""


class SweepLogWarning(GaussppWarning):
    """A line of a sweep's JSON-lines log cannot be read: it is skipped and its task runs again."""
