"""Success means within ``constraint_tol``: no lane calls a run a success whose recorded residual (or energy
balance) is beyond the run's ``constraint_tol`` (:mod:`gausspp.simulation.tolerance`).

The reference is computed here from the trajectory's recorded arrays alone: the largest ``|g_i|/(1 + ‖q‖∞)`` and
``|Φ_i|/(1 + ‖v‖∞)`` over the samples."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import gausspp as gp
from gausspp.simulation.tolerance import within_tolerance


def _relative_residual(traj: gp.Trajectory) -> float:
    """The largest residual of the run relative to the size of the state, from the recorded arrays."""
    if not traj.g.size:
        return 0.0
    q_size = 1.0 + np.abs(traj.q).max(axis=1)
    v_size = 1.0 + np.abs(traj.v).max(axis=1)
    return float(max((np.abs(traj.g) / q_size[:, None]).max(), (np.abs(traj.residual) / v_size[:, None]).max()))


def _run(name: str, options: dict, constraint_tol: float, t_end: float | None = None) -> gp.Trajectory:
    scene = gp.scenes.get(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gp.DriftWarning)
        return gp.simulate(
            scene.model,
            scene.q0,
            scene.v0,
            t_end or scene.t_end,
            constraint_tol=constraint_tol,
            throw=False,
            **options,
        )


#: one run per lane: (scene, options, the lane expected, a tolerance the run breaks, one it keeps)
LANE_RUNS = [
    ("pendulum", {"method": "rk4", "dt": 0.05, "lane": "python"}, "python", 1e-9, 1e-3),
    ("pendulum", {"method": "rk4", "dt": 0.05}, "compiled", 1e-9, 1e-3),
    ("pendulum", {"method": "RK45", "rtol": 1e-5, "atol": 1e-5}, "scipy", 1e-9, 1e-3),
    ("pendulum", {"method": "cvodes", "solver": "direct", "rtol": 1e-6, "atol": 1e-6}, "cvodes", 1e-10, 1e-3),
    ("bouncing-pendulum", {"rtol": 1e-6, "atol": 1e-6}, "events", 1e-10, 1e-3),
    ("overhead-crane", {"rtol": 1e-5, "atol": 1e-5}, "servo", 1e-12, 1e-3),
]


@pytest.mark.parametrize(("name", "options", "lane", "broken", "kept"), LANE_RUNS, ids=[r[2] for r in LANE_RUNS])
def test_no_lane_calls_a_run_beyond_constraint_tol_a_success(
    name: str, options: dict, lane: str, broken: float, kept: float
) -> None:
    """Each lane, run coarsely: with a ``constraint_tol`` below its drift the run is ``"drifted"`` (reached the end,
    not a success, a DriftWarning naming the tolerance); with one above it, a success; and in both, success holds
    exactly when the residual computed here from the recorded arrays is within the tolerance."""
    loose = _run(name, options, kept)
    assert loose.lane == lane and loose.status == "success", loose.message
    drift = _relative_residual(loose)
    assert drift <= kept
    scene = gp.scenes.get(name)
    with pytest.warns(gp.DriftWarning, match=r"not within constraint_tol"):
        tight = gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, constraint_tol=broken, throw=False, **options)
    assert tight.status == "drifted" and not tight.success
    assert tight.t[-1] == pytest.approx(loose.t[-1]) and tight.t.size == loose.t.size  # the run is whole
    assert "constraint_tol" in tight.message and "t=" in tight.message
    residual_beyond = _relative_residual(tight) > broken
    assert residual_beyond or "energy balance" in tight.message  # what it names is really beyond the tolerance


def test_the_dt_10_run_is_no_success_at_any_tolerance() -> None:
    """The issue's example: rk4 with dt = 10 on the pendulum fails with the DriftError, not a success."""
    scene = gp.scenes.get("pendulum")
    for tol in (1e-8, 1e-2):
        traj = gp.simulate(
            scene.model, scene.q0, scene.v0, 20.0, method="rk4", dt=10.0, throw=False, constraint_tol=tol
        )
        assert traj.status == "failed" and isinstance(traj.failure, gp.DriftError)


def test_the_check_catches_a_residual_put_in_by_hand() -> None:
    """The negative control: a successful trajectory whose recorded residual of one sample is raised to twice the
    tolerance is marked drifted (at that sample's time, naming its row); the unchanged trajectory is not."""
    scene = gp.scenes.get("pendulum")
    tol = 1e-6
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0, constraint_tol=tol)
    assert traj.success and _relative_residual(traj) < tol
    assert within_tolerance(scene.model, traj, tol) is traj
    i = traj.t.size // 2
    g = traj.g.copy()
    g[i, 0] = 2 * tol * (1 + np.abs(traj.q[i]).max())
    with pytest.warns(gp.DriftWarning):
        marked = within_tolerance(scene.model, replace(traj, g=g), tol)
    assert marked.status == "drifted"
    assert f"t={traj.t[i]:.6g}" in marked.message and repr(scene.model.row_names[0]) in marked.message


def test_the_check_catches_an_energy_balance_put_in_by_hand() -> None:
    """The energy part: the reaction's work shifted after mid-run by 1e-5 of the largest kinetic energy (the
    energy scale: the total energy is conserved) breaks the balance and marks the run drifted, though the residuals
    pass; shifted by 1e-8 it does not."""
    scene = gp.scenes.get("pendulum")
    tol = 1e-8
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 1.0, constraint_tol=tol)
    assert traj.success
    model = scene.model
    kinetic = [
        0.5 * v @ model.evaluate_data(t, q, v, lam).A @ v
        for t, q, v, lam in zip(traj.t, traj.q, traj.v, traj.lam, strict=True)
    ]
    scale = max(kinetic)
    work = traj.work_reaction.copy()
    work[traj.t.size // 2 :] += 1e-8 * scale
    assert within_tolerance(scene.model, replace(traj, work_reaction=work), tol).success
    work[traj.t.size // 2 :] += 1e-5 * scale
    with pytest.warns(gp.DriftWarning, match="energy balance"):
        marked = within_tolerance(scene.model, replace(traj, work_reaction=work), tol)
    assert marked.status == "drifted"


def test_a_failed_run_stays_failed() -> None:
    """The check judges finished runs only: a failure keeps its status and its error."""
    scene = gp.scenes.get("pendulum")
    traj = gp.simulate(scene.model, scene.q0, scene.v0, 20.0, method="rk4", dt=10.0, throw=False)
    assert within_tolerance(scene.model, traj, 1e-30) is traj


def test_the_command_line_says_drifted_and_takes_constraint_tol(capsys: pytest.CaptureFixture[str]) -> None:
    """``gausspp run`` of the coarse rk4 pendulum: exit 1 with "drifted" at the default 1e-8; exit 0 with
    ``--constraint-tol 1e-3``."""
    from gausspp import cli

    assert cli.main(["run", "pendulum", "--method", "rk4", "--dt", "0.05", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "the run drifted" in err and "constraint_tol=1e-08" in err
    assert cli.main(["run", "pendulum", "--method", "rk4", "--dt", "0.05", "--quiet", "--constraint-tol", "1e-3"]) == 0
