"""Names along a trajectory's axes: coordinates, velocities, constraint rows, reaction unknowns, contact rows.

A :class:`~gausspp.Trajectory` made by :func:`gausspp.simulate` carries its model's names
(:class:`Labels`); the labelled views (:mod:`gausspp.simulation.labelled`) and the plots read them. Each
recorded array is laid out along these axes (:data:`DIMS`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np

#: The axes of each recorded array after the time axis (a name of :class:`Labels`), in the trajectory's order.
DIMS: dict[str, tuple[str, ...]] = {
    "q": ("coordinate",),
    "v": ("velocity",),
    "lam": ("lam_state",),
    "a": ("velocity",),
    "u": ("unknown",),
    "reaction": ("velocity",),
    "compulsion": (),
    "residual": ("row",),
    "g": ("row",),
    "margin": (),
    "energy": (),
    "work_reaction": (),
    "work_forces": (),
    "contact_force": ("contact_row",),
    "tracking_error": (),
    "saturated": ("unknown",),
    "gap": ("contact_row",),
}

#: What each array is (``long_name`` in the labelled views).
MEANING: dict[str, str] = {
    "t": "time",
    "q": "configuration coordinates q",
    "v": "velocities v (q̇, or quasi-velocities)",
    "lam": "state λ of realizations that carry it",
    "a": "accelerations",
    "u": "reaction unknowns (λ, or λ̇ of a flywheel)",
    "reaction": "reaction R = [T] − F",
    "compulsion": "Gauss's compulsion Z of the step",
    "residual": "constraint residual Φ(q, v, t)",
    "g": "holonomic residual g(q, t) (0 on velocity-level rows)",
    "margin": "realizability margin σ_min of the normalized S",
    "energy": "total energy",
    "work_reaction": "work of the reaction since t[0]",
    "work_forces": "work of the non-conservative forces since t[0]",
    "contact_force": "multipliers of unilateral contacts (≥ 0)",
    "tracking_error": "how far bounded servos fall short",
    "saturated": "reaction unknown at a bound",
    "gap": "gap g(q, t) of each unilateral contact row",
    "energy_balance": "ΔE − ΔW_reaction − ΔW_forces since t[0] (0 for an exact motion)",
}

#: Units the library knows whatever the model's own units (the model's quantities carry the user's units).
UNITS: dict[str, str] = {"margin": "1", "saturated": "1"}

#: The generic name of the ``i``-th entry along an axis without names.
_GENERIC = dict(coordinate="q", velocity="v", row="row", unknown="u", lam_state="lam", contact_row="contact")

#: The array whose second axis tells each axis's size.
_SIZED_BY = dict(coordinate="q", velocity="v", row="residual", unknown="u", lam_state="lam", contact_row="gap")


@dataclass(frozen=True)
class Labels:
    """One name per entry along each axis; an empty tuple where the names are not known.

    Attributes
    ----------
    coordinate, velocity : tuple of str
        The mechanism's ``coordinate_names`` and ``velocity_names`` (empty if it has none).
    row : tuple of str
        Bilateral constraint rows (``model.row_names``).
    unknown : tuple of str
        Reaction unknowns: a constraint's name, with ``[i]`` where it has several columns.
    lam_state : tuple of str
        The ``λ`` state's entries (the unknowns that are ``λ̇``).
    contact_row : tuple of str
        Unilateral contact rows (``model.contact_row_names``).
    """

    coordinate: tuple[str, ...] = ()
    velocity: tuple[str, ...] = ()
    row: tuple[str, ...] = ()
    unknown: tuple[str, ...] = ()
    lam_state: tuple[str, ...] = ()
    contact_row: tuple[str, ...] = ()

    def as_dict(self) -> dict[str, tuple[str, ...]]:
        """``{axis: names}`` for every axis."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def complete(self, traj: Any) -> Labels:
        """Every axis named for ``traj``'s arrays: the known names where they fit, generic ones (``q0``, ``q1``…)
        elsewhere; velocities take the coordinates' names where there are as many."""
        named = self.as_dict()
        sizes = {axis: width(getattr(traj, key)) for axis, key in _SIZED_BY.items()}
        if not named["velocity"] and named["coordinate"] and sizes["velocity"] == sizes["coordinate"]:
            named["velocity"] = named["coordinate"]
        out = {
            axis: names if len(names) == sizes[axis] else tuple(f"{_GENERIC[axis]}{i}" for i in range(sizes[axis]))
            for axis, names in named.items()
        }
        return Labels(**out)


def width(arr: np.ndarray) -> int:
    """Entries per sample of a ``(N, n)`` array (0 for an empty default)."""
    arr = np.asarray(arr)
    return int(arr.shape[1]) if arr.ndim == 2 else 0


def unknown_names(groups: Any) -> tuple[str, ...]:
    """One name per reaction unknown from the model's constraint groups (their names and column slices)."""
    out: list[str] = []
    for group in groups:
        n = group.cols.stop - group.cols.start
        out += [group.name] if n == 1 else [f"{group.name}[{i}]" for i in range(n)]
    return tuple(out)


def model_labels(model: Any) -> Labels:
    """The names of ``model``'s axes (:class:`~gausspp.Model`)."""
    mech, unknown = model.mechanism, unknown_names(model.groups)
    return Labels(
        coordinate=tuple(mech.coordinate_names or ()),
        velocity=tuple(mech.velocity_names or ()),
        row=tuple(model.row_names),
        unknown=unknown,
        lam_state=tuple(unknown[c] for c in model.lam_columns),
        contact_row=tuple(model.contact_row_names),
    )
