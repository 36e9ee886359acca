"""The closest points of two segments, as casadi expressions (the cores of capsules, spheres and cylinders)."""

from __future__ import annotations

from typing import Any

import casadi as ca


def closest_points(p1: Any, q1: Any, p2: Any, q2: Any) -> tuple[Any, Any]:
    """The closest points of the segments ``p1q1`` and ``p2q2`` (Ericson, *Real-Time Collision Detection* §5.1.9),
    with casadi's branches; a degenerate segment is a point."""
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = ca.dot(d1, d1), ca.dot(d2, d2), ca.dot(d2, r)
    c, b = ca.dot(d1, r), ca.dot(d1, d2)
    tiny = 1e-300

    def clamp(x: Any) -> Any:
        return ca.fmin(ca.fmax(x, 0), 1)

    denom = a * e - b * b
    s = ca.if_else(denom > 1e-12 * (a * e + tiny), clamp((b * f - c * e) / (denom + tiny)), 0)
    t = (b * s + f) / (e + tiny)
    s_lo, s_hi = clamp(-c / (a + tiny)), clamp((b - c) / (a + tiny))
    s = ca.if_else(t < 0, s_lo, ca.if_else(t > 1, s_hi, s))
    t = clamp(t)
    s = ca.if_else(a > tiny, s, 0)
    t = ca.if_else(e > tiny, t, 0)
    s = ca.if_else(ca.logic_and(a <= tiny, e > tiny), 0, s)
    t = ca.if_else(ca.logic_and(a <= tiny, e > tiny), clamp(f / (e + tiny)), t)
    t = ca.if_else(ca.logic_and(e <= tiny, a > tiny), 0, t)
    s = ca.if_else(ca.logic_and(e <= tiny, a > tiny), clamp(-c / (a + tiny)), s)
    return p1 + d1 * s, p2 + d2 * t
