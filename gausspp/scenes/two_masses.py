"""Two masses on a line (paper §1, docs/theory.md §6.1): one constraint, two realizations, two motions.

Masses ``m1, m2`` on a line, a force ``F`` on ``m2`` (and, if ``k > 0``, a spring ``−k x₂`` to a
wall, which makes the exact motion a sinusoid), the constraint ``ẋ₂ − ẋ₁ = 0``.

* ``realization="ideal"`` — a rigid rod: both accelerate at ``F/(m1 + m2)``; the rod's
  tension is ``λ = m1 F/(m1 + m2)``.
* ``realization="servo"`` — a follower force on ``m1`` (Béghin, ``M = (1, 0)``): ``m2`` feels
  only ``F``, so both accelerate at ``F/m2``; the servo force is ``λ = m1 F/m2``; the virtual
  displacements are ``δx₁ = 0``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError, UnknownNameError
from ..model.constraints import Constraint
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Force, Ideal
from .scene import Scene

REALIZATIONS = ("ideal", "servo")


def build(
    m1: float = 1.0,
    m2: float = 3.0,
    F: float = 2.0,
    realization: str = "ideal",
    v: float = 0.0,
    k: float = 0.0,
    l: float = 1.0,
    t_end: float = 1.0,
) -> Scene:
    """Two masses joined by a rod (ideal) or kept together by a follower force on ``m1`` (servo).

    Parameters
    ----------
    m1 : float
        Mass of the first body, the one the servo's follower force pushes (kg). Allowed: > 0.
    m2 : float
        Mass of the second body, the one ``F`` and the spring act on (kg). Allowed: > 0.
    F : float
        Constant force on the second mass, along the line (N). Allowed: any finite number.
    realization : str
        How ``ẋ₂ − ẋ₁ = 0`` is kept: by a rigid rod (``'ideal'``) or by a follower force on ``m1``
        (``'servo'``) (-). Allowed: one of 'ideal', 'servo'.
    v : float
        Initial velocity of both masses (m/s). Allowed: any finite number.
    k : float
        Stiffness of the spring from the second mass to the wall, force ``−k x₂`` (N/m). Allowed: ≥ 0 (0: no
        spring).
    l : float
        Length of the rod: the initial distance ``x₂ − x₁``, with ``x₁ = 0`` at the start (m). Allowed: > 0.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if realization not in REALIZATIONS:
        raise UnknownNameError(f"two-masses: realization={realization!r} is unknown; use one of {list(REALIZATIONS)}")
    if not (m1 > 0 and m2 > 0 and k >= 0 and l > 0):
        raise InputError(f"two-masses: need m1, m2 > 0, k ≥ 0 and l > 0, got m1={m1}, m2={m2}, k={k}, l={l}")
    body = Lagrangian(
        n=2,
        T=lambda q, v, t: 0.5 * m1 * v[0] ** 2 + 0.5 * m2 * v[1] ** 2,
        F=lambda q, v, t: [0, F],
        V=lambda q, t: 0.5 * k * q[1] ** 2,
    )
    real = Ideal() if realization == "ideal" else Force(M=lambda q, v, t: [1, 0])
    model = Model(body, [Constraint(lambda q, v, t: v[1] - v[0], name="rod", realization=real)])
    inertia = m1 + m2 if realization == "ideal" else m2  # what F − k x₂ accelerates
    q0, v0 = np.array([0.0, float(l)]), np.array([v, v])

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        if k == 0:
            acc = F / inertia
            return q0 + v0 * t + 0.5 * acc * t * t, v0 + acc * t
        w = np.sqrt(k / inertia)
        rest = F / k  # x₂ about its equilibrium: harmonic with frequency w
        x2 = rest + (q0[1] - rest) * np.cos(w * t) + v / w * np.sin(w * t)
        v2 = -(q0[1] - rest) * w * np.sin(w * t) + v * np.cos(w * t)
        return np.array([x2 - l, x2]), np.array([v2, v2])

    return Scene(
        name="two-masses",
        model=model,
        q0=q0,
        v0=v0,
        coordinates=("x₁ (m)", "x₂ (m)"),
        lam0=None,
        t_end=t_end,
        exact=exact,
        description="two masses on a line, rod (ideal) or follower force (servo); paper §1",
        params=dict(m1=m1, m2=m2, F=F, realization=realization, v=v, k=k, l=l, t_end=t_end),
        drawing=drawing,
    )


def drawing(q: np.ndarray) -> dict[str, Any]:
    """The two masses on the line ``y = 0`` and the rod between them; the reaction on each mass, along the line
    (:attr:`Scene.drawing`)."""
    m1, m2 = (q[0], 0.0), (q[1], 0.0)
    return {"segments": [(m1, m2)], "points": [m1, m2], "reaction": [(m1, (0, None)), (m2, (1, None))]}
