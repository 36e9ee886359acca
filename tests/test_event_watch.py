"""The phase watch of the event-driven lane against closed forms, on a synthetic flight ``g(t) = w t − ½ γ t²``."""

from __future__ import annotations

import numpy as np
import pytest

from gausspp.simulation.event_watch import PhaseWatch

W, GAMMA = 1.3, 9.81  # take-off rate and deceleration of the gap
SUNK = 1e-12  # a contact leaves an impact on g = 0 to round-off: here a little below it
LANDING = (W + np.sqrt(W * W - 2 * GAMMA * SUNK)) / GAMMA  # the later root of w t − ½ γ t² − SUNK


def _flight(t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The gap and its rate as functions of the state ``y = (g, ġ)`` (one contact)."""
    return np.array([y[0]]), np.array([y[1]])


def _dense(t: float) -> np.ndarray:
    return np.array([W * t - 0.5 * GAMMA * t * t - SUNK, W - GAMMA * t])


def _no_forces(t: float, y: np.ndarray) -> np.ndarray:
    return np.zeros(0)


@pytest.mark.parametrize("departing", [True, False])
def test_a_contact_that_leaves_and_lands_within_one_step_is_caught_at_its_landing(departing: bool) -> None:
    """One step from take-off (g ≈ 0, ġ > 0) to beyond the landing: the departing watch finds the landing; a
    contact watched on its gap from the start settles on the take-off itself (where g crosses its round-off)."""
    watch = PhaseWatch(0.0, _dense(0.0), [0], {0} if departing else set(), 0, _flight, _no_forces)
    t_end = 1.5 * LANDING
    hit = watch.first_event(0.0, t_end, _dense(t_end), _dense)
    assert hit is not None
    if departing:
        assert abs(hit[0] - LANDING) <= 1e-14 * LANDING
        assert 0 not in watch.departing  # watched on the gap from its apex on
    else:
        assert abs(hit[0] - LANDING) > 0.1 * LANDING  # the negative control: without the departing watch


def test_the_apex_alone_changes_the_watch_and_ends_nothing() -> None:
    watch = PhaseWatch(0.0, _dense(0.0), [0], {0}, 0, _flight, _no_forces)
    t1, t2 = 0.8 * LANDING, 1.2 * LANDING  # past the apex (LANDING/2), still above the floor; then below
    assert watch.first_event(0.0, t1, _dense(t1), _dense) is None
    assert 0 not in watch.departing
    hit = watch.first_event(t1, t2, _dense(t2), _dense)
    assert hit is not None and abs(hit[0] - LANDING) <= 1e-14 * LANDING


def test_the_landing_is_located_to_round_off_from_a_far_start() -> None:
    """A step whose start is far above the floor (no Hermite data of that step: the bracket's middle to start)."""
    watch = PhaseWatch(0.1, _dense(0.1), [0], set(), 0, _flight, _no_forces)
    watch.ends.clear()
    hit = watch.first_event(0.1, 1.9 * LANDING, _dense(1.9 * LANDING), _dense)
    assert hit is not None and abs(hit[0] - LANDING) <= 1e-14 * LANDING
