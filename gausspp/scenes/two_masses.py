"""Two masses on a line (paper §1, DESIGN §6.1): one constraint, two realizations, two motions.

Masses ``m1, m2`` on a line, a force ``F`` on ``m2``, the constraint ``ẋ₂ − ẋ₁ = 0``.

* ``realization="ideal"`` — a rigid rod: both accelerate at ``F/(m1 + m2)``; the rod's
  tension is ``λ = m1 F/(m1 + m2)``.
* ``realization="servo"`` — a follower force on ``m1`` (Béghin, ``M = (1, 0)``): ``m2`` feels
  only ``F``, so both accelerate at ``F/m2``; the servo force is ``λ = m1 F/m2``; the virtual
  displacements are ``δx₁ = 0``.
"""

from __future__ import annotations

import numpy as np

from ..constraints import Constraint
from ..errors import InputError, UnknownNameError
from ..frontends import Lagrangian
from ..model import Model
from ..realizations import Force, Ideal
from ._scene import Scene

REALIZATIONS = ("ideal", "servo")


def build(
    m1: float = 1.0, m2: float = 3.0, F: float = 2.0, realization: str = "ideal", v: float = 0.0, t_end: float = 1.0
) -> Scene:
    """Two masses joined by a rod (ideal) or kept together by a follower force on ``m1`` (servo)."""
    if realization not in REALIZATIONS:
        raise UnknownNameError(f"two-masses: realization={realization!r} is unknown; use one of {list(REALIZATIONS)}")
    if not (m1 > 0 and m2 > 0):
        raise InputError(f"two-masses: masses must be positive, got m1={m1}, m2={m2}")
    body = Lagrangian(
        n=2,
        T=lambda q, v, t: 0.5 * m1 * v[0] ** 2 + 0.5 * m2 * v[1] ** 2,
        F=lambda q, v, t: [0, F],
    )
    real = Ideal() if realization == "ideal" else Force(M=lambda q, v, t: [1, 0])
    model = Model(body, [Constraint(lambda q, v, t: v[1] - v[0], name="rod", realization=real)])
    acc = F / (m1 + m2) if realization == "ideal" else F / m2
    q0, v0 = np.array([0.0, 1.0]), np.array([v, v])

    def exact(t: float) -> tuple[np.ndarray, np.ndarray]:
        return q0 + v0 * t + 0.5 * acc * t * t, v0 + acc * t

    return Scene(
        name="two-masses",
        model=model,
        q0=q0,
        v0=v0,
        lam0=None,
        t_end=t_end,
        exact=exact,
        description="two masses on a line, rod (ideal) or follower force (servo); paper §1",
        params=dict(m1=m1, m2=m2, F=F, realization=realization, v=v, t_end=t_end),
    )
