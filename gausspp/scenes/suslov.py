"""Suslov's problem: where the motion of the scene ``"rigid-body-servo"`` with ``n = l`` goes.

A rigid body about a fixed point with the ideal constraint ``(ω, l) = 0`` (``l`` a unit body
vector): ``Iω̇ + ω × Iω = μ l``. In a right-handed orthonormal body basis ``(e₁, e₂, l)`` put
``ω = ω₁e₁ + ω₂e₂``, ``I₂`` the 2×2 block of ``I`` on ``(e₁, e₂)`` and ``b = ((Il, e₁), (Il, e₂))``.
Since ``Iω = (I₂ω, b·ω)``, the components of ``ω × Iω`` along ``e₁, e₂`` are ``(b·ω)(ω₂, −ω₁)``, and
Euler's equations projected on the plane read

    I₂ ω̇ = −(b·ω) (ω₂, −ω₁).

The energy ``E = ½ ωᵀI₂ω`` is conserved; ``ω`` is steady iff ``c = b·ω = 0``, i.e.
``ω = s (b₂, −b₁)``, which in body vectors is ``ω = −s l × Il``. Near it ``ċ = s (bᵀI₂⁻¹b) c``, so
of the two steady rotations on the energy ellipse the one with ``s < 0`` attracts every other
motion as ``t → +∞`` (and the one with ``s > 0`` repels): ``ω∞ = κ l × Il`` with ``κ > 0`` fixed by
``½ ω∞ᵀIω∞ = E``, approached like ``exp(−|s| bᵀI₂⁻¹b t)``. If ``l`` is a principal axis (``b = 0``)
every rotation in the plane is steady.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .rigid import inertia_matrix, on_plane, unit_vector


def _plane(inertia: Any, l: Any, omega0: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    I = inertia_matrix("suslov", inertia)
    l_ = unit_vector("suslov", "l", l)
    w0 = on_plane("suslov", omega0, l_)
    return I, l_, w0, np.cross(l_, I @ l_)


def steady_rotation(inertia: Any, l: Any, omega0: Any) -> np.ndarray:
    """The steady rotation that Suslov's motion from ``omega0`` tends to as ``t → +∞``.

    Parameters
    ----------
    inertia : (3,) or (3, 3) array
        Principal moments or the inertia tensor, body axes.
    l : (3,) array
        The constraint's axis, ``(ω, l) = 0`` (normalized here).
    omega0 : (3,) array
        Initial body angular velocity (projected onto ``(ω, l) = 0`` here).

    Returns
    -------
    (3,) array
        ``ω∞ = κ l × Il``, ``κ ≥ 0``, with the energy ``½ ωᵀIω`` of ``omega0``. If ``l`` is a
        principal axis, or ``omega0`` is already the unstable steady rotation, ``omega0`` itself
        (projected), since the motion is then steady.
    """
    I, l_, w0, d = _plane(inertia, l, omega0)
    scale = np.linalg.norm(I, 2)
    if np.linalg.norm(d) <= 1e-14 * scale:  # l principal: b = 0, every rotation is steady
        return w0
    if abs(np.dot(I @ l_, w0)) <= 1e-14 * scale * np.linalg.norm(w0):  # c = b·ω = 0: steady already
        return w0
    energy = 0.5 * w0 @ I @ w0
    return np.sqrt(2.0 * energy / (d @ I @ d)) * d


def approach_rate(inertia: Any, l: Any, omega0: Any) -> float:
    """The exponential rate ``|s| bᵀI₂⁻¹b`` at which ``ω(t) → ω∞`` (0 if ``l`` is principal)."""
    I, l_, w0, d = _plane(inertia, l, omega0)
    w_inf = steady_rotation(I, l_, w0)
    if np.linalg.norm(d) <= 1e-14 * np.linalg.norm(I, 2):
        return 0.0
    e1 = d / np.linalg.norm(d)
    e2 = np.cross(l_, e1)
    E = np.column_stack([e1, e2])
    I2, b = E.T @ I @ E, E.T @ I @ l_
    s = np.linalg.norm(w_inf) / np.linalg.norm(b)
    return float(s * b @ np.linalg.solve(I2, b))
