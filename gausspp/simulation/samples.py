"""What a lane hands to the recording (:mod:`gausspp.simulation.recording`): the states it accepted."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError


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
        where none was solved), for the recording to replay (:meth:`~gausspp.step.equality.kernel.QPParts.replay`).
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


def fixed_grid(t0: float, t_end: float, dt: float) -> np.ndarray:
    """The times of a fixed-step run: ``t0 + i·dt``, the last step shortened to end at ``t_end``."""
    n_steps = int(np.ceil((t_end - t0) / dt - 1e-9))
    times = t0 + dt * np.arange(n_steps + 1)
    times[-1] = t_end
    return times


def kept_steps(times: np.ndarray, record: Any) -> np.ndarray:
    """Which of a fixed-step run's ``times`` to keep (one rule for every lane): every ``record``-th and the last, or
    those at the ``record`` times, which must lie on the grid (to 1e-9 of the times' size)."""
    last = times.size - 1
    if np.isscalar(record):
        idx = np.arange(0, last + 1, max(int(record), 1))  # type: ignore[arg-type]  # checked by check_record
        return idx if idx[-1] == last else np.append(idx, last)
    wanted = np.asarray(record, float)
    tol = 1e-9 * max(1.0, float(np.abs(times).max(initial=0.0)))
    idx = np.searchsorted(times, wanted - tol)
    if np.any(idx > last) or np.any(np.abs(times[np.minimum(idx, last)] - wanted) > tol):
        raise InputError("record times must lie on the fixed-step grid t0 + i·dt within [t0, t_end]")
    return np.unique(idx)
