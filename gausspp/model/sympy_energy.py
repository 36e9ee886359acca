"""The energy of a ``sympy.physics.mechanics`` system: ``E = T + V`` and the non-conservative forces, for
:func:`gausspp.from_sympy` (so that ``Trajectory.energy`` and the energy balance ``dE/dt = v·(F_nc + R)`` work).

* ``LagrangesMethod``: the Lagrangian ``L`` holds the conservative forces, so ``E = Σ q̇ᵢ ∂L/∂q̇ᵢ − L`` (the
  energy function, ``T + V`` for a natural system) and ``F_nc`` are the generalized forces of its ``forcelist``.
* ``KanesMethod`` and ``System``: ``T`` is sympy's ``kinetic_energy`` of the bodies; a force constant in the
  inertial frame (gravity, any constant push) is conservative with ``V = −F·r_P`` (``r_P`` from a point fixed in
  that frame: the system's ``fixed_point``, or a point the bodies' positions lead to whose velocity there is set
  to zero); every other load (forces that depend on the state or on time, torques) is non-conservative, its
  generalized force ``Σ F·∂v_P/∂uᵢ + M·∂ω_B/∂uᵢ``.

Where the energy cannot be told (no fixed point to measure a constant force from), :func:`energy_parts` returns
``None`` and the model records no energy, as before.
"""

from __future__ import annotations

from typing import Any

from ..errors import InputError


def energy_parts(source: Any, speeds: list[Any], kd: dict[Any, Any], me: Any) -> tuple[Any, list[Any]] | None:
    """``(E, F_nc)`` as sympy expressions in the coordinates and ``speeds`` (``kd``: ``q̇ → K(q, u)``), or None."""
    if isinstance(source, me.LagrangesMethod):
        return _lagrange(source, me)
    if isinstance(source, me.System):
        loads = list(source.loads) + [load for actuator in source.actuators for load in actuator.to_loads()]
        return _kane_like(source.frame, source.bodies, loads, speeds, kd, me, source.fixed_point)
    if isinstance(source, me.KanesMethod):
        frame = getattr(source, "_inertial", None)
        if frame is None:
            return None
        return _kane_like(frame, source.bodies or [], source.loads or [], speeds, kd, me, None)
    return None


def _lagrange(method: Any, me: Any) -> tuple[Any, list[Any]] | None:
    L = getattr(method, "_L", None)  # sympy keeps the Lagrangian only here (1.12–1.14)
    if L is None:
        return None
    L = L[0] if getattr(L, "shape", ()) else L  # kept as a 1×1 matrix
    t = me.dynamicsymbols._t
    qd = [qi.diff(t) for qi in method.q]
    energy = sum(qdi * L.diff(qdi) for qdi in qd) - L
    return energy, _generalized_forces(method.inertial, method.loads or [], qd, {}, me)


def _kane_like(
    frame: Any, bodies: Any, loads: Any, speeds: list[Any], kd: dict[Any, Any], me: Any, fixed: Any
) -> tuple[Any, list[Any]] | None:
    zero = me.dynamicsymbols._t * 0
    kinetic = me.msubs(me.kinetic_energy(frame, *bodies), kd) if bodies else zero
    potential, others = zero, []
    for load in loads:
        where, vector = load[0], load[1]
        if isinstance(where, me.Point) and _constant(vector, frame, me):
            origin = fixed or _fixed_point(where, frame, kd, me)
            if origin is None:
                return None
            potential -= me.msubs(vector.dot(where.pos_from(origin)), kd)
        else:
            others.append(load)
    return kinetic + potential, [me.msubs(f, kd) for f in _generalized_forces(frame, others, speeds, kd, me)]


def _constant(vector: Any, frame: Any, me: Any) -> bool:
    """Whether ``vector`` is constant in ``frame``: no dynamic symbol (coordinate, speed or time) in its components."""
    return not any(me.find_dynamicsymbols(c) or c.has(me.dynamicsymbols._t) for c in vector.to_matrix(frame))


def _fixed_point(point: Any, frame: Any, kd: dict[Any, Any], me: Any) -> Any:
    """A point fixed in ``frame`` that ``point``'s position leads to (breadth first): its velocity there set to zero
    *and* ``point``'s position from it differentiating to ``point``'s velocity — a rolling contact point has zero
    velocity but moves, and a potential measured from it would be wrong (checked at two random states)."""
    seen, queue = {point}, [point]
    while queue:
        p = queue.pop(0)
        vel = getattr(p, "_vel_dict", {}).get(frame)
        if vel is not None and vel == 0 and _stays(point, p, frame, kd, me):
            return p
        for other in getattr(p, "_pos_dict", {}):
            if other not in seen:
                seen.add(other)
                queue.append(other)
    return None


def _stays(point: Any, origin: Any, frame: Any, kd: dict[Any, Any], me: Any) -> bool:
    """Whether ``d/dt (r_point − r_origin) = v_point`` in ``frame`` (at two seeded random states)."""
    import random

    gap = [me.msubs(c, kd) for c in (point.pos_from(origin).dt(frame) - point.vel(frame)).to_matrix(frame)]
    symbols = sorted({s for c in gap for s in (*me.find_dynamicsymbols(c), *c.free_symbols)}, key=str)
    rng = random.Random(31)
    for _ in range(2):
        values = {s: rng.uniform(0.3, 1.7) for s in symbols}
        if any(abs(complex(c.xreplace(values).evalf())) > 1e-9 for c in gap):
            return False
    return True


def _generalized_forces(frame: Any, loads: Any, speeds: list[Any], kd: dict[Any, Any], me: Any) -> list[Any]:
    """``Σ F·∂v_P/∂uᵢ`` over forces on points and ``Σ M·∂ω_B/∂uᵢ`` over torques on frames (velocities written in
    the speeds through ``kd``)."""
    out: list[Any] = [me.dynamicsymbols._t * 0] * len(speeds)  # sympy zeros (msubs needs sympy expressions)
    for where, vector in ((load[0], load[1]) for load in loads):
        if isinstance(where, me.Point):
            motion = where.vel(frame)
        elif isinstance(where, me.ReferenceFrame):
            motion = where.ang_vel_in(frame)
        else:
            raise InputError(f"from_sympy: a load acts on {type(where).__name__}, not a Point or a ReferenceFrame")
        partials = me.partial_velocity([motion.subs(kd) if kd else motion], speeds, frame)[0]
        for i, partial in enumerate(partials):
            out[i] += vector.dot(partial)
    return out
