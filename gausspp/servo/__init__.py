"""Servo-constraints the one-step formula cannot reach: their diagnosis and their index reduction.

:func:`servo_diagnosis` says how a model's actuators reach its constraints (relative degrees, Blajer's geometry,
the DAE's index); :func:`simulate_servo` follows the constraints by differentiating them as often as the
actuators need (:mod:`gausspp.servo.index_reduction`); :func:`replay` integrates the free mechanism under the forces it
returned (open loop), to show that they alone keep the path.
"""

from .diagnosis import ServoDiagnosis, servo_diagnosis
from .index_reduction import ServoTrajectory, simulate_servo
from .replay import Replay, replay

__all__ = ["Replay", "ServoDiagnosis", "ServoTrajectory", "replay", "servo_diagnosis", "simulate_servo"]
