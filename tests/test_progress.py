"""A long run shows how far it is and how long it still needs."""

from __future__ import annotations

import importlib
import io
import warnings

import numpy as np
import pytest

import gausspp as gp
from gausspp.simulation.progress import Progress

simulate_module = importlib.import_module("gausspp.simulation.inputs")  # the limits of a run
progress_module = importlib.import_module("gausspp.simulation.progress")


class Terminal(io.StringIO):
    """A stream that says it is a terminal (the bar is drawn on terminals only)."""

    def isatty(self) -> bool:
        return True


def test_progress_line_states_the_fraction_and_the_time_left() -> None:
    stream = Terminal()
    progress = Progress(1000, "run", enabled=True, every=0.0, stream=stream)
    progress.update(250)
    progress.close()
    text = stream.getvalue()
    assert "run: 25% (250 of 1e+03 steps), about" in text and "left" in text and text.endswith("\n")


def test_a_disabled_progress_writes_nothing() -> None:
    stream = Terminal()
    progress = Progress(1000, "run", enabled=False, every=0.0, stream=stream)
    progress.update(500)
    progress.close()
    assert stream.getvalue() == ""


def test_no_progress_bar_off_a_terminal() -> None:
    """A log file or a pipe gets no bar (the LongRunWarning has announced the run)."""
    stream = io.StringIO()
    progress = Progress(1000, "run", enabled=True, every=0.0, stream=stream)
    progress.update(500)
    progress.close()
    assert stream.getvalue() == ""


def test_a_long_fixed_step_run_reports_progress(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
    """With the threshold lowered to 10 steps (instead of 10⁶) a 400-step rk4 run stepped from Python warns and
    reports progress (``lane="python"``: by default rk4 runs as one compiled call, which reports nothing)."""
    monkeypatch.setattr(simulate_module, "LONG_RUN_STEPS", 10)
    monkeypatch.setattr(simulate_module, "PROGRESS_EVERY", 50)
    monkeypatch.setattr(Progress, "__init__", _every_call(Progress.__init__))
    monkeypatch.setattr(progress_module, "is_terminal", lambda stream: True)  # stderr is captured here
    scene = gp.scenes.get("two-masses")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        traj = gp.simulate(scene.model, scene.q0, scene.v0, 4.0, method="rk4", dt=0.01, lane="python")
    assert traj.success and len(traj) == 401
    assert any(issubclass(w.category, gp.LongRunWarning) and "standard error" in str(w.message) for w in caught)
    err = capsys.readouterr().err
    assert "gausspp.simulate (rk4):" in err and "% (" in err and "left" in err
    assert np.isfinite(traj.q).all()


def _every_call(init):  # the same Progress, reporting at every update
    def patched(self, *args, **kwargs):
        kwargs["every"] = 0.0
        init(self, *args, **kwargs)

    return patched
