"""The Scene record: a model with its initial data, horizon and exact solution if known."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..model import Model


@dataclass(frozen=True)
class Scene:
    """A reference problem ready to step or simulate.

    Attributes
    ----------
    name : str
    model : Model
    q0, v0 : arrays
        Initial configuration and velocity (on the constraint).
    lam0 : array or None
        Initial ``λ`` for realizations that carry it.
    t_end : float
        Suggested horizon.
    exact : callable ``t -> (q, v)`` or None
        The exact motion where one is known.
    description : str
        One line for listings.
    params : dict
        The parameters the scene was built with.
    """

    name: str
    model: Model
    q0: np.ndarray
    v0: np.ndarray
    lam0: np.ndarray | None
    t_end: float
    exact: Callable[[float], tuple[np.ndarray, np.ndarray]] | None
    description: str
    params: dict[str, Any] = field(default_factory=dict)
