"""Servo-constraints the one-step formula cannot reach: their diagnosis and their index-reduction route.

:func:`servo_diagnosis` says how a model's actuators reach its constraints (relative degrees, Blajer's kind,
the DAE's index); :func:`simulate_servo` follows the constraints by differentiating them as often as the
actuators need (:mod:`gausspp.servo.route`); :func:`replay` integrates the free mechanism under the forces it
returned (open loop), to show that they alone keep the path.
"""

from .diagnosis import ServoDiagnosis, servo_diagnosis
from .replay import Replay, replay
from .route import ServoTrajectory, simulate_servo

__all__ = ["Replay", "ServoDiagnosis", "ServoTrajectory", "replay", "servo_diagnosis", "simulate_servo"]
