"""What a frictional run returns (:class:`FrictionRun`) and how its samples are gathered (:class:`Record`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class FrictionRun:
    """A frictional motion: samples ``t, q, v``; per sample the contact ``modes``, normal forces ``N`` (one
    column per contact) and friction forces ``F`` (one column per slip component, contacts in order) and the
    ``energy``; the ``events`` (time, kind, contact);
    ``status`` ``"success"`` or ``"failed"`` with the ``message`` and the ``failure`` (what was computed is kept)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    modes: list[tuple[str, ...]]
    N: np.ndarray
    F: np.ndarray
    energy: np.ndarray
    contact_names: tuple[str, ...]
    events: list[dict[str, Any]] = field(default_factory=list)
    status: str = "success"
    message: str = ""
    failure: Exception | None = None

    @property
    def success(self) -> bool:
        return self.status == "success"


class Record:
    """The samples of a run as blocks (one per phase segment or chunk of steps), joined by :meth:`run`."""

    def __init__(self, nq: int, nv: int, n_contacts: int, n_friction: int) -> None:
        self.nq, self.nv, self.c, self.nd = nq, nv, n_contacts, n_friction
        self.t: list[np.ndarray] = []
        self.y: list[np.ndarray] = []
        self.N: list[np.ndarray] = []
        self.F: list[np.ndarray] = []
        self.energy: list[np.ndarray] = []
        self.modes: list[tuple[str, ...]] = []

    def add(self, t: Any, y: Any, modes: tuple[str, ...], N: Any, F: Any, energy: Any) -> None:
        """Samples at the times ``t`` (``k`` of them): states ``y (k, nq+nv)``, forces ``N (k, c)``, ``F (k, nd)``,
        energies ``(k,)``, all under ``modes``."""
        t = np.atleast_1d(np.asarray(t, float))
        k = t.size
        self.t.append(t)
        self.y.append(np.asarray(y, float).reshape(k, self.nq + self.nv))
        self.N.append(np.asarray(N, float).reshape(k, self.c))
        self.F.append(np.asarray(F, float).reshape(k, self.nd))
        self.energy.append(np.asarray(energy, float).reshape(k))
        self.modes.extend([modes] * k)

    def run(self, names: tuple[str, ...], events: list[dict[str, Any]]) -> FrictionRun:
        def join(parts: list[np.ndarray], *shape: int) -> np.ndarray:
            return np.concatenate(parts) if parts else np.zeros((0, *shape))

        Y = join(self.y, self.nq + self.nv)
        return FrictionRun(
            t=join(self.t),
            q=Y[:, : self.nq],
            v=Y[:, self.nq :],
            modes=self.modes,
            N=join(self.N, self.c),
            F=join(self.F, self.nd),
            energy=join(self.energy),
            contact_names=names,
            events=events,
        )
