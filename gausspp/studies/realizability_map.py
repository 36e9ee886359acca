"""Where a servo torque along ``n`` can keep ``(ω, l) = 0``: the margin over the sphere of torque axes.

A rigid body about a fixed point must keep ``(ω, l) = 0`` by a torque ``λn`` along a body axis ``n``
(Béghin realization, paper §2). The step is solvable iff ``(I⁻¹n, l) ≠ 0`` (condition (12)). This study
returns the numbers; :func:`gausspp.plot.realizability_map` draws them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError, ShapeError
from ..validation import inertia_matrix, unit_vector

#: The name quoted in the messages of this study's errors.
_OWNER = "realizability_grid"


@dataclass(frozen=True)
class RealizabilityGrid:
    """The numbers behind :func:`gausspp.plot.realizability_map`.

    Attributes
    ----------
    inertia : (3, 3) array
        The body's inertia tensor ``I`` (body axes).
    l : (3,) array
        Unit normal of the constraint ``(ω, l) = 0``.
    lon, lat : (n_lon,), (n_lat,) arrays
        Longitudes in ``[−180°, 180°]`` and latitudes in ``[−90°, 90°]`` of the grid, degrees.
    n : (n_lat, n_lon, 3) array
        The unit torque axes ``n = (cos φ cos ψ, cos φ sin ψ, sin φ)`` (``φ`` latitude, ``ψ`` longitude).
    margin : (n_lat, n_lon) array
        The realizability margin of the servo torque along ``n``.
    pole : (3,) array
        ``I⁻¹l / |I⁻¹l|``: the true zero set is the great circle ``(n, pole) = 0``.
    true_circle, naive_circle : (m, 3) arrays
        Unit vectors on the true zero set ``(I⁻¹n, l) = 0`` and on the naive circle ``n ⟂ l``.
    true_margin, naive_margin : (m,) arrays
        The margin along them.
    """

    inertia: np.ndarray
    l: np.ndarray
    lon: np.ndarray
    lat: np.ndarray
    n: np.ndarray
    margin: np.ndarray
    pole: np.ndarray
    true_circle: np.ndarray
    naive_circle: np.ndarray
    true_margin: np.ndarray
    naive_margin: np.ndarray

    @property
    def principal(self) -> bool:
        """True if ``l`` is a principal axis (``I⁻¹l ∥ l``): then both circles coincide."""
        return bool(np.linalg.norm(np.cross(self.pole, self.l)) < 1e-12)


def inertia_tensor(inertia: Any, owner: str = _OWNER) -> np.ndarray:
    """Principal moments ``(3,)`` or a tensor ``(3, 3)`` as a symmetric positive definite 3×3 array.

    Raises :class:`~gausspp.errors.InputError` naming ``owner`` if the tensor is not symmetric
    positive definite (then ``(I⁻¹n, n)`` is no metric and the margin no cosine).
    """
    arr = inertia_matrix(owner, inertia)
    if not np.allclose(arr, arr.T) or np.linalg.eigvalsh(arr).min() <= 0:
        raise InputError(
            f"{owner}: inertia must be symmetric positive definite, got {arr.tolist()}; "
            "give three positive principal moments or a symmetric tensor with positive eigenvalues"
        )
    return arr


def servo_margin(inertia: Any, l: Any, n: Any) -> np.ndarray:
    """Realizability margin of a servo torque along ``n`` keeping ``(ω, l) = 0``, for many ``n`` at once.

    With ``A = I``, ``J = lᵀ`` and ``D = n`` (paper §2, condition (12)) the margin of
    :func:`gausspp.realizability.margin` is the cosine of the angle between ``l`` and ``n`` in
    the metric ``I⁻¹``:

        margin(n) = |(I⁻¹n, l)| / √((I⁻¹l, l) (I⁻¹n, n)),

    zero exactly on the great circle ``(n, I⁻¹l) = 0``.

    Parameters
    ----------
    inertia : (3,) or (3, 3) array
    l : (3,) array
    n : (..., 3) array
        Torque axes (need not be unit vectors).

    Returns
    -------
    (...) array
    """
    I = inertia_tensor(inertia, "servo_margin")
    lv = unit_vector("servo_margin", "l", l)
    nv = np.asarray(n, dtype=float)
    if nv.shape[-1:] != (3,):
        raise ShapeError(f"servo_margin: n must have 3 components in its last axis, got shape {nv.shape}")
    Il = np.linalg.solve(I, lv)
    In = np.linalg.solve(I, nv.reshape(-1, 3).T).T.reshape(nv.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.abs(nv @ Il) / np.sqrt((lv @ Il) * np.einsum("...i,...i->...", nv, In))
    return np.nan_to_num(out, nan=0.0)


def great_circle(normal: np.ndarray, m: int) -> np.ndarray:
    """``m`` unit vectors, evenly spaced, on the great circle ``(n, normal) = 0`` (``normal`` a unit vector)."""
    e1 = np.cross(normal, np.eye(3)[int(np.argmin(np.abs(normal)))])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    s = np.linspace(0.0, 2 * np.pi, m, endpoint=False)
    return np.outer(np.cos(s), e1) + np.outer(np.sin(s), e2)


def sphere_grid(resolution: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Longitudes, latitudes (degrees) and the unit vectors ``n`` of a ``resolution``-degree grid."""
    if not (np.isfinite(resolution) and 0 < resolution <= 30):
        raise InputError(f"{_OWNER}: resolution is a grid step in degrees, 0 < resolution ≤ 30; got {resolution}")
    lon = np.linspace(-180.0, 180.0, int(round(360 / resolution)) + 1)
    lat = np.linspace(-90.0, 90.0, int(round(180 / resolution)) + 1)
    LON, LAT = np.meshgrid(np.radians(lon), np.radians(lat))
    n = np.stack([np.cos(LAT) * np.cos(LON), np.cos(LAT) * np.sin(LON), np.sin(LAT)], axis=-1)
    return lon, lat, n


def realizability_grid(
    inertia: Any = (1.0, 2.0, 3.0), l: Any = (1.0, 1.0, 1.0), resolution: float = 1.0, circle_points: int = 720
) -> RealizabilityGrid:
    """The realizability margin of a servo torque along ``n`` over the sphere of directions ``n``.

    The bad axes form the great circle ``n ⟂ I⁻¹l``. The paper calls them "``n`` orthogonal to
    ``l``", which is the same circle only when ``l`` is a principal axis (``I⁻¹l ∥ l``). See
    :func:`servo_margin` for the margin.

    Parameters
    ----------
    inertia : (3,) or (3, 3) array
        Principal moments or an inertia tensor (symmetric positive definite).
    l : (3,) array
        The constraint's normal (normalized here).
    resolution : float
        Grid step in degrees of longitude and latitude.
    circle_points : int
        Points on each of the two circles.

    Returns
    -------
    RealizabilityGrid
    """
    I, lv = inertia_tensor(inertia), unit_vector(_OWNER, "l", l)
    lon, lat, n = sphere_grid(resolution)
    pole = unit_vector(_OWNER, "I⁻¹l", np.linalg.solve(I, lv))
    true_circle, naive_circle = great_circle(pole, circle_points), great_circle(lv, circle_points)
    return RealizabilityGrid(
        inertia=I,
        l=lv,
        lon=lon,
        lat=lat,
        n=n,
        margin=servo_margin(I, lv, n),
        pole=pole,
        true_circle=true_circle,
        naive_circle=naive_circle,
        true_margin=servo_margin(I, lv, true_circle),
        naive_margin=servo_margin(I, lv, naive_circle),
    )
