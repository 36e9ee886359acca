"""How a model's actuators reach its constraints (:mod:`gausspp.step.servo_reach`), as a report."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..model.model import Model
from ..step.servo_reach import find_reach, geometry


@dataclass(frozen=True)
class ServoDiagnosis:
    """The reach of the actuators at a state.

    Attributes
    ----------
    rows : list of str
        The constraint rows.
    unextended : tuple of int
        Each row's relative degree: the derivative of the constraint in which a force first appears (2 when
        the one-step formula applies).
    degrees, chains : tuple of int
        The degrees after the dynamic extension, and the integrators it put in front of each actuator.
    geometry : {"orthogonal", "oblique", "tangential", "mixed"}
        Blajer's geometry of the realization, from ``S = J A⁻¹ D``.
    index : int
        The servo DAE's differentiation index, ``max rᵢ + 1`` (3 for a realizable one-step servo).
    """

    rows: list[str]
    unextended: tuple[int, ...]
    degrees: tuple[int, ...]
    chains: tuple[int, ...]
    geometry: str
    index: int

    @property
    def one_step(self) -> bool:
        """Whether the one-step formula (``model.step``, ``gp.simulate``) applies: every force acts at once."""
        return self.index <= 3 and not any(self.chains)

    def describe(self) -> str:
        """One sentence for a message."""
        reach = ", ".join(f"{r!r}: {d}" for r, d in zip(self.rows, self.degrees, strict=True))
        extension = (
            f" after putting {', '.join(f'{c} integrator(s)' for c in self.chains if c)} in front of the actuators"
            if any(self.chains)
            else ""
        )
        article = "an" if self.geometry[0] in "aeiou" else "a"
        return f"{article} {self.geometry} realization: relative degrees {reach}{extension}; DAE index {self.index}"


def servo_diagnosis(model: Model, t: float, q: Any, v: Any) -> ServoDiagnosis:
    """How the actuators of ``model`` reach its constraints at ``(t, q, v)`` (see :class:`ServoDiagnosis`)."""
    t, q, v, lam = model.checked_state(t, q, v, None)
    reach = find_reach(model, t, q, v)
    d = model.step_data(t, q, v, lam)
    return ServoDiagnosis(
        rows=list(model.row_names),
        unextended=reach.unextended,
        degrees=reach.degrees,
        chains=reach.extended.chains,
        geometry=geometry(model, d.A, d.J, d.D),
        index=reach.index,
    )
