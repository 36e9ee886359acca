"""Smooth rest-to-rest profiles for prescribed paths (the servo scenes :mod:`.overhead_crane` and
:mod:`.spring_chain_servo`), as numpy polynomials in ``t`` and as expressions casadi can differentiate.

A servo-constraint of relative degree ``r`` needs its prescribed path ``r`` times differentiable (index
reduction differentiates it symbolically), and a path that starts and ends at rest with all those derivatives
zero makes the rest states at both ends consistent. The Hermite smoothstep of order ``p`` is the polynomial
of degree ``2p + 1`` with

    σ_p(0) = 0,  σ_p(1) = 1,  σ_p⁽ʲ⁾(0) = σ_p⁽ʲ⁾(1) = 0  (1 ≤ j ≤ p);

``p = 4`` gives ``126τ⁵ − 420τ⁶ + 540τ⁷ − 315τ⁸ + 70τ⁹``. Its derivative is ``σ_p′(τ) = K τᵖ (1 − τ)ᵖ`` with
``K = (2p + 1)! / (p!)²``, so in the centred variable ``u = 2τ − 1`` (``τ(1 − τ) = (1 − u²)/4``)

    σ_p = ½ + (K / 2^(2p+1)) Σₖ C(p, k) (−1)ᵏ u^(2k+1) / (2k + 1),

computed here in exact rational arithmetic. The polynomials are kept in ``u`` (numpy's ``domain = [0, T]``,
``window = [−1, 1]``): their coefficients are small, so even the 12th derivative (the chain of 6 masses) is
evaluated to about 1e-10 relative, where the monomial coefficients in ``t`` lose every digit.
"""

from __future__ import annotations

from fractions import Fraction
from math import comb, factorial
from typing import Any

import casadi as ca
import numpy as np
from numpy.polynomial import Polynomial


def _centred(coefficients: list[Fraction] | list[float], duration: float) -> Polynomial:
    """The polynomial ``Σ cₖ uᵏ`` of ``u = 2t/duration − 1``, as a numpy polynomial in ``t``."""
    return Polynomial([float(c) for c in coefficients], domain=[0.0, duration], window=[-1.0, 1.0])


def rest_to_rest(p: int, duration: float, distance: float = 1.0) -> Polynomial:
    """``distance · σ_p(t / duration)``: from 0 to ``distance``, derivatives of orders 1 … ``p`` zero at both ends."""
    K = Fraction(factorial(2 * p + 1), factorial(p) ** 2) / 2 ** (2 * p + 1)
    coefficients = [Fraction(0)] * (2 * p + 2)
    coefficients[0] = Fraction(1, 2)
    for k in range(p + 1):
        coefficients[2 * k + 1] = K * comb(p, k) * (-1) ** k / (2 * k + 1)
    return distance * _centred(coefficients, duration)


def bump(order: int, duration: float, height: float = 1.0) -> Polynomial:
    """``height · 4ᵏ τᵏ (1 − τ)ᵏ = height (1 − u²)ᵏ`` with ``k = order + 1``: ``height`` at mid-time, zero with its
    derivatives up to ``order`` at both ends (``order = 4``: ``2¹⁰ τ⁵ (1 − τ)⁵``)."""
    k = order + 1
    coefficients = [0.0] * (2 * k + 1)
    for j in range(k + 1):
        coefficients[2 * j] = comb(k, j) * (-1.0) ** j
    return height * _centred(coefficients, duration)


def evaluate(poly: Polynomial, t: Any, duration: float) -> Any:
    """``poly(t)`` with ``t`` clamped to ``[0, duration]`` (at rest outside the move).

    ``t`` may be a number, an array or a casadi symbol: then Horner's scheme in the centred variable, in
    casadi operations (which casadi differentiates exactly), clamped with ``fmin``/``fmax``.
    """
    if isinstance(t, (ca.SX, ca.MX, ca.DM)):
        offset, scale = poly.mapparms()
        u = offset + scale * ca.fmin(ca.fmax(t, 0.0), duration)
        value: Any = 0.0
        for c in poly.coef[::-1]:
            value = value * u + float(c)
        return value
    return poly(np.clip(np.asarray(t, dtype=float), 0.0, duration))
