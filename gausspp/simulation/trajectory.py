"""The Trajectory record: what a simulation computed, sample by sample (docs/theory.md §5)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import labelled
from .labels import Labels


@dataclass(frozen=True)
class Trajectory:
    """Arrays over the recorded samples (first axis: time).

    Attributes
    ----------
    t : (N,) array
    q : (N, nq) array
    v : (N, nv) array
    lam : (N, n_lam) array
        ``λ`` of realizations that carry it (empty second axis otherwise).
    a : (N, nv) array
        Accelerations.
    u : (N, m) array
        Reaction unknowns (``λ`` or ``λ̇``).
    reaction : (N, nv) array
        ``R = [T] − F``.
    compulsion : (N,) array
        Gauss's compulsion ``Z`` of each step.
    residual : (N, k) array
        The constraint ``Φ(q, v, t)`` along the trajectory (drift).
    g : (N, k) array
        Holonomic residuals ``g(q, t)`` (0 on velocity-level rows).
    margin : (N,) array
        Realizability margin.
    energy : (N,) array
        Total energy (NaN if the model does not know it).
    work_reaction, work_forces : (N,) arrays
        Accumulated work of the reaction and of the non-conservative forces since ``t[0]``
        (``work_forces`` NaN if the model does not know its forces' power).
    status : {"success", "drifted", "failed"}
        ``"drifted"``: reached ``t_end``, but a residual or the energy balance left ``constraint_tol``.
    message : str
        Why a run failed or drifted (empty on success).
    failure : GaussppError or None
        The error that stopped a failed run, with its details (for a
        :class:`~gausspp.RealizabilityError`: ``t``, ``constraint``, ``margin``); ``None`` on success. Not
        saved by :meth:`save` (its ``message`` is).
    method, solver : str
    lane : str
        The lane that ran the method (:mod:`gausspp.simulation.lanes`): ``"compiled"`` (the whole run as
        one casadi graph), ``"python"`` (fixed steps from Python), ``"scipy"``, ``"cvodes"``, ``"events"``
        (contact phases) or ``"servo"`` (index reduction of a servo-constraint,
        :mod:`gausspp.simulation.servo_lane`); ``""`` for a trajectory not made by :func:`gausspp.simulate`.
    route : str
        How each step eliminated the acceleration: ``"dense"`` or ``"sparse"`` (the model's ``route``,
        :mod:`gausspp.step.equality.sparse`); ``""`` for a trajectory not made by :func:`gausspp.simulate`.
    steps, rhs_evaluations : int
    contact_force : (N, n_contact_rows) array
        Multipliers of unilateral contacts (≥ 0; empty second axis without contacts).
    tracking_error : (N,) array
        How far bounded servos fall short (0 unless an actuator saturates; zeros without bounds).
    saturated : (N, m) bool array
        Reaction unknowns at a bound.
    events : tuple of dict
        Impacts and contact changes, in order (``{"t", "kind", "contact", ...}``); two samples
        share the time of an impact: before and after the velocity jump. An impact names the
        contact row that approached (``speed_before`` → ``speed_after``, its ``impulse``) and the
        velocity ``jump`` it belongs to: rows hit at the same instant share one jump and so its
        ``kinetic_energy_before``/``_after`` (count a jump's energy loss once).
    gap : (N, n_contact_rows) array
        The gap ``g(q, t)`` of every unilateral contact row at each sample (≥ 0 up to the integration
        tolerance; 0 while a contact is closed); empty second axis without contacts.
    friction_force, slip : (N, n_slip) arrays
        Frictional contacts only (the ``"friction"`` lane): each contact's friction force and slip velocity, one
        column per slip component, contacts in order (``contact_force`` holds their normal forces, ``gap`` their
        gaps); empty second axis otherwise.
    modes : tuple of tuples of str
        Frictional contacts only: each contact's mode at each sample (``"open"``, ``"stick"``, ``"slide"``).
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    lam: np.ndarray
    a: np.ndarray
    u: np.ndarray
    reaction: np.ndarray
    compulsion: np.ndarray
    residual: np.ndarray
    g: np.ndarray
    margin: np.ndarray
    energy: np.ndarray
    work_reaction: np.ndarray
    work_forces: np.ndarray
    status: str
    message: str
    method: str
    solver: str
    steps: int
    rhs_evaluations: int
    contact_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    tracking_error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    saturated: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=bool))
    events: tuple[dict[str, Any], ...] = ()
    gap: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    friction_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    slip: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    modes: tuple[tuple[str, ...], ...] = ()
    lane: str = ""
    route: str = ""
    labels: Labels = field(default_factory=Labels)
    failure: Exception | None = field(default=None, compare=False, repr=False)

    @property
    def success(self) -> bool:
        """True if the run reached ``t_end`` within its ``constraint_tol`` (status ``"success"``; a run that reached
        it beyond the tolerance is ``"drifted"``, one that stopped early ``"failed"``)."""
        return self.status == "success"

    def energy_balance(self) -> np.ndarray:
        """``ΔE − ΔW_reaction − ΔW_forces`` since the first sample: zero for an exact motion.

        A free accuracy check. Valid for kinetic and potential energies that do not depend on
        time explicitly; NaN where the model does not know its energy or its forces' power.
        """

        def since_first(x: np.ndarray) -> np.ndarray:
            return x - x[0] if x.size else x

        return since_first(self.energy) - since_first(self.work_reaction) - since_first(self.work_forces)

    def max_residual(self) -> float:
        """Largest ``|Φ|`` and ``|g|`` over the trajectory."""
        return float(max(np.max(np.abs(self.residual), initial=0.0), np.max(np.abs(self.g), initial=0.0)))

    def to_xarray(self) -> Any:
        """The trajectory as an ``xarray.Dataset`` (needs ``pip install 'gausspp[data]'``).

        Dims ``time`` × ``coordinate`` (``q``), ``velocity`` (``v``, ``a``, ``reaction``), ``lam_state``,
        ``unknown`` (``u``, ``saturated``), ``row`` (``residual``, ``g``), ``contact_row`` (``contact_force``,
        ``gap``), each named from the model (``q0``, ``q1``… where the model has no names); every recorded
        array a variable (with ``energy_balance``), the run's settings (method, solver, lane, route, status,
        message, steps, events as JSON) attributes.
        """
        return labelled.to_xarray(self)

    def to_pandas(self) -> Any:
        """The trajectory as a ``pandas.DataFrame`` indexed by time ``t``: columns ``q[name]``, ``v[name]``,
        ``u[name]``, ``residual[row]`` …, and ``margin``, ``compulsion``, ``energy`` …; settings in ``.attrs``
        (needs ``pip install 'gausspp[data]'``)."""
        return labelled.to_pandas(self)

    def save(self, path: str | os.PathLike[str], attrs: dict[str, Any] | None = None, overwrite: bool = False) -> Path:
        """Write the trajectory to ``path``: ``.npz`` (numpy only) or ``.nc`` (netCDF, needs
        ``gausspp[data]``), chosen by the suffix; ``attrs`` (strings, numbers) are stored too.
        :func:`load_trajectory` reads it back, so that the run can be verified later (:func:`gausspp.verify`).
        Written whole or not at all (a temporary name, then renamed); a file at ``path`` that is not a saved
        trajectory is replaced only with ``overwrite=True``."""
        return labelled.save(self, path, attrs, overwrite)

    def __len__(self) -> int:
        return int(self.t.size)


def load_trajectory(path: str | os.PathLike[str]) -> Trajectory:
    """The trajectory written by :meth:`Trajectory.save` to ``path`` (``.npz`` or ``.nc``), arrays, names
    and settings; fields the file lacks take their defaults."""
    stored = labelled.read(path, Trajectory.__dataclass_fields__)
    defaults: dict[str, Any] = dict(status="success", message="", method="", solver="", steps=0, rhs_evaluations=0)
    n = len(stored["t"])
    for key in ("q", "v", "lam", "a", "u", "reaction", "residual", "g"):
        defaults[key] = np.zeros((n, 0))
    for key in ("compulsion", "margin", "energy", "work_reaction", "work_forces"):
        defaults[key] = np.full(n, np.nan)
    return Trajectory(**{**defaults, **stored})
