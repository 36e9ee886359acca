"""What a lane hands to the recording (:mod:`gausspp.simulation.recording`): the states it accepted."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Samples:
    """The states ``y = (q, v, λ, W_R, W_F)`` a lane kept, and how it got them.

    Attributes
    ----------
    t : (N,) array
    y : (N, nq + nv + n_lam + 2) array
    steps, evaluations : int
        Accepted steps and right-hand-side evaluations of the run (the recording adds none).
    failure : Exception or None
        Why the run stopped before ``t_end`` (the samples are what it computed until then).
    method, solver : str
        The method's name and the step's label (``"direct"``, a QP backend, ``"gauss-qp:…"``).
    active : list of tuples, optional
        Contact runs: the active contact rows of the phase each sample belongs to.
    backend : str or None
        Contact runs: the ``backend`` argument (one registry name for the decisions and the phases).
    events : tuple of dict
        Contact runs: impacts, touches and lift-offs (see :class:`~gausspp.Trajectory`).
    qp_solutions : (N, m + k) array, optional
        Compiled QP runs: the QP's solution ``(z, y)`` of the step at each sample, as the run solved it (NaN
        where none was solved), for the recording to replay (:meth:`~gausspp.step.kernel.QPParts.replay`).
    """

    t: np.ndarray
    y: np.ndarray
    steps: int
    evaluations: int
    failure: Exception | None
    method: str
    solver: str
    active: list[tuple[int, ...]] | None = None
    backend: str | None = None
    events: tuple[dict[str, Any], ...] = ()
    qp_solutions: np.ndarray | None = None
