"""Figures (matplotlib, an optional extra: ``pip install gausspp[plots]``).

Every function draws results it is given and returns a matplotlib :class:`~matplotlib.figure.Figure`;
saving and showing it are the caller's choice. A non-interactive backend (Agg) is used when no display
is available. matplotlib is imported only when a figure is drawn. The numbers behind the figures are
computed by the studies: :mod:`gausspp.studies.realizability_map` (:func:`realizability_grid`,
:func:`servo_margin`) and :mod:`gausspp.studies.figures` (:func:`three_realizations_runs`,
:func:`skate_runs`).

Figures (one module of this package each)
-----------------------------------------
trajectory          ``q(t)``, ``v(t)`` and optionally the phase portrait ``(qᵢ, vᵢ)``     (motion)
reaction_over_time  ``u(t)`` (``λ`` or ``λ̇``), compulsion ``Z(t)`` and the realizability margin  (motion)
friction            slip, normal and friction forces and energy of frictional runs  (friction)
stick_slip_map      a block at rest on a slope: sticks or slides, over (α, μ)  (friction)
contacts            recorded gaps ``g(t)``, contact forces and energy of a run with contacts  (impacts)
realizability_map   the margin of a servo torque along ``n`` over the sphere of directions ``n``  (margin_map)
three_realizations  one constraint ``(ω, l) = 0`` kept ideally, by a servo torque, by a flywheel  (realizations)
skate               the nonholonomic and the vakonomic skate in the plane  (realizations)
verification        the minimizing variation ``δx(t)`` of the integral principle (23)  (integral)
work_precision      error against run time (the study of :mod:`gausspp.report`)  (runtime)
animate             the mechanism moving, from its scene's ``drawing``, saved as GIF or MP4  (animation)
"""

from __future__ import annotations

from .animation import animate
from .base import palette, pyplot
from .friction import friction, stick_slip_map
from .impacts import contacts
from .integral import verification
from .margin_map import realizability_map
from .motion import reaction_over_time, trajectory
from .realizations import THREE_LABELS, skate, three_realizations
from .runtime import save_work_precision, work_precision

__all__ = [
    "THREE_LABELS",
    "animate",
    "contacts",
    "friction",
    "palette",
    "pyplot",
    "reaction_over_time",
    "realizability_map",
    "save_work_precision",
    "skate",
    "stick_slip_map",
    "three_realizations",
    "trajectory",
    "verification",
    "work_precision",
]
