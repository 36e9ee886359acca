"""Mixed realizations (paper (19)–(22), docs/theory.md §2): inertia and a controlled force together.

A particle of mass ``m`` in the plane, ``q = (x, y)``, on anisotropic springs
``V = ½(kx x² + ky y²)``, kept on the track ``Φ = ẏ − c ẋ = 0`` (``J = (−c, 1)``). The
realization is mixed: an inertial part with

    ``N = ẏ + β (x ẏ − y ẋ)``,  ``N_v = (−β y, 1 + β x)``,  ``[N] = 2β (−ẏ, ẋ)``

(the ``β`` term is gyroscopic, so ``[N]`` is not zero) and a force along the constant direction
``M`` (default ``(1, 0)``: a push along ``x``).

* ``law="proportional"`` (19), ``λ′ = λ``: ``R = −λ̇ N_v − λ[N] + λ M``, so ``D = −N_vᵀ``.
  Realizable iff ``S = J A⁻¹ D = −(J·N_v)/m = −(1 + β(x + c y))/m ≠ 0``.
* ``law="rate"`` (22), ``λ′ = λ̇``: ``R = −λ̇ N_v − λ[N] + λ̇ M``, so ``D = Mᵀ − N_vᵀ``.
  Realizable iff ``J·(M − N_v) ≠ 0``; with ``M = (1, 0)`` that is ``1 + c + β(x + c y) ≠ 0``.

``λ`` is a state with ``λ(0) = lam0``. No closed form is known; the checks are QP ≡ direct,
the constraint, the reaction's form and the energy balance ``E − E₀ = W_R``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError, ShapeError, UnknownNameError
from ..model.constraints import Constraint
from ..model.mechanism import Lagrangian
from ..model.model import Model
from ..model.realizations import Mixed
from ..validation import array
from .scene import Scene

LAWS = ("proportional", "rate")


def build(
    law: str = "proportional",
    m: float = 1.0,
    kx: float = 1.0,
    ky: float = 4.0,
    c: float = 0.5,
    beta: float = 0.2,
    M: Any = (1.0, 0.0),
    lam0: float = 0.5,
    x0: float = 1.0,
    t_end: float = 5.0,
) -> Scene:
    """Particle in the plane on the track ẏ = cẋ, kept by a mixed realization (law (19) or (22)).

    Parameters
    ----------
    law : str
        The force multiplier: ``λ′ = λ`` (``'proportional'``, paper (19)) or ``λ′ = λ̇`` (``'rate'``, paper
        (22)); the scenes ``mixed-proportional`` and ``mixed-rate`` fix it (-). Allowed: one of 'proportional',
        'rate'.
    m : float
        Mass of the particle (kg). Allowed: > 0.
    kx : float
        Stiffness of the spring along x, ``V = ½ kx x²`` (N/m). Allowed: any finite number; ≥ 0 for a restoring
        spring (the sign is not checked).
    ky : float
        Stiffness of the spring along y, ``V = ½ ky y²`` (N/m). Allowed: any finite number; ≥ 0 for a restoring
        spring (the sign is not checked).
    c : float
        Slope of the track ``ẏ = c ẋ`` (-). Allowed: any finite number.
    beta : float
        Gyroscopic coefficient ``β`` of the inertial part ``N = ẏ + β (x ẏ − y ẋ)`` (1/m). Allowed: any finite
        number; where the realizability condition of the module docstring fails the step raises a
        RealizabilityError.
    M : (2,) array_like
        Direction of the controlled force, whose part of the reaction is ``λ′ M`` (1/s if λ′ = λ, - if λ′ = λ̇).
        Allowed: a finite 2-vector.
    lam0 : float
        Initial value of the multiplier ``λ``, a state (kg·m/s). Allowed: any finite number.
    x0 : float
        Initial position x of the particle, which starts at rest at ``(x0, 0)`` (m). Allowed: any finite number.
    t_end : float
        Suggested horizon of a simulation (s). Allowed: > 0.
    """
    if law not in LAWS:
        raise UnknownNameError(f"mixed: law={law!r} is unknown; use one of {list(LAWS)}")
    if not m > 0:
        raise InputError(f"mixed: the mass must be positive, got m={m}")
    direction = array("mixed", "M", M).ravel()
    if direction.shape != (2,):
        raise ShapeError(f"mixed: M must be a finite 2-vector (the force direction), got {M!r}")
    body = Lagrangian(
        n=2,
        T=lambda q, v, t: 0.5 * m * (v[0] ** 2 + v[1] ** 2),
        V=lambda q, t: 0.5 * (kx * q[0] ** 2 + ky * q[1] ** 2),
    )
    realization = Mixed(
        N=lambda q, v, t: v[1] + beta * (q[0] * v[1] - q[1] * v[0]),
        M=lambda q, v, t: [direction.tolist()],
        law=law,
        lam0=lam0,
    )
    model = Model(body, [Constraint(lambda q, v, t: v[1] - c * v[0], name="track", realization=realization)])
    name = f"mixed-{law}"
    paper = "(19)" if law == "proportional" else "(22)"
    return Scene(
        name=name,
        model=model,
        q0=np.array([float(x0), 0.0]),
        v0=np.zeros(2),
        coordinates=("x (m)", "y (m)"),
        lam0=np.array([float(lam0)]),
        t_end=t_end,
        exact=None,
        description=f"particle on a track, mixed realization {paper}: N with gyroscopic [N] and a force along M",
        params=dict(law=law, m=m, kx=kx, ky=ky, c=c, beta=beta, M=direction.tolist(), lam0=lam0, x0=x0, t_end=t_end),
    )


def build_mixed_proportional(**params: Any) -> Scene:
    """Particle on a track kept by a mixed realization, force multiplier λ′ = λ (paper (19))."""
    return build(law="proportional", **params)


def build_mixed_rate(**params: Any) -> Scene:
    """Particle on a track kept by a mixed realization, force multiplier λ′ = λ̇ (paper (22))."""
    return build(law="rate", **params)
