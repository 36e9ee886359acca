"""Success means within tolerance, for the energy too (:mod:`gausspp.simulation.energy_audit`)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import gausspp as gp
from gausspp.simulation import energy_audit


def _spring(k: float = 100.0, t_dependent: bool = False, known_forces: bool = True) -> gp.Model:
    """A unit mass on a spring along x, held on the line y = 0: a linear row no step can violate, so nothing but
    the energy can show a wrong motion."""
    stiffness = (lambda t: k * (1 + t)) if t_dependent else (lambda t: k)
    if known_forces:
        mech = gp.Lagrangian(
            n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2), V=lambda q, t: 0.5 * stiffness(t) * q[0] ** 2
        )
    else:  # the same spring, its energy given but not which of its forces are non-conservative
        mech = gp.MassMatrix(
            n=2,
            A=lambda q, t: ca.DM.eye(2),
            f=lambda q, v, t: ca.vertcat(-k * q[0], 0),
            energy=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2) + 0.5 * k * q[0] ** 2,
        )
    return gp.Model(mech, [gp.Holonomic(lambda q, t: q[1], name="on the line")])


def test_a_step_too_long_for_a_model_without_rows_fails_on_its_energy() -> None:
    """rk4 at dt = 0.5 on a spring of period 0.63 s: every step answers, no row can drift, the energy grows by
    orders — a failed run naming the energy balance; at dt = 1e-3 the same motion is a success (the control),
    its balance within 1e-9 of the energy (measured 3.5e-11 J of 0.5 J)."""
    model = _spring()
    q0, v0 = np.array([0.1, 0.0]), np.array([0.0, 0.0])
    with pytest.raises(gp.DriftError, match=r"left its energy balance at t=.*drift_tol") as caught:
        gp.simulate(model, q0, v0, 5.0, method="rk4", dt=0.5)
    assert caught.value.constraint == "energy balance" and abs(caught.value.residual) > 0.05
    kept = caught.value.trajectory  # type: ignore[attr-defined]
    assert kept.status == "failed" and kept.t[-1] == caught.value.t
    fine = gp.simulate(model, q0, v0, 5.0, method="rk4", dt=1e-3)
    assert fine.success and np.abs(fine.energy_balance()).max() < 1e-9 * 0.5
    # negative control: the residual audit alone has nothing to look at here
    with pytest.warns(gp.DriftWarning, match="energy balance"):  # reached the end, but no success
        loose = gp.simulate(model, q0, v0, 5.0, method="rk4", dt=0.5, drift_tol=1e9)
    assert loose.status == "drifted" and loose.t[-1] == 5.0 and np.abs(loose.energy_balance()).max() > 1.0


def test_a_methods_own_energy_error_passes() -> None:
    """Symplectic Euler keeps a spring's energy within O(dt) (it oscillates, it does not drift): no failure, a
    success where constraint_tol allows 1 % of the energy scale, "drifted" (not a success) at the default 1e-8."""
    q0, v0 = np.array([0.1, 0.0]), np.array([0.0, 0.0])
    traj = gp.simulate(_spring(), q0, v0, 10.0, method="symplectic-euler", dt=1e-3, constraint_tol=1e-4)
    assert traj.success
    with pytest.warns(gp.DriftWarning, match="energy balance"):
        strict = gp.simulate(_spring(), q0, v0, 10.0, method="symplectic-euler", dt=1e-3)
    assert strict.status == "drifted" and strict.t[-1] == 10.0
    assert 0 < np.abs(traj.energy_balance()).max() < 0.1 * 0.5  # measured 0.5 % of the energy 0.5 J


def test_the_audit_applies_only_where_the_balance_closes() -> None:
    """An energy with explicit time, or forces whose power is unknown, close no balance: not audited."""
    assert energy_audit.closes(_spring())
    assert not energy_audit.closes(_spring(t_dependent=True))
    assert not energy_audit.closes(_spring(known_forces=False))
    q0, v0 = np.array([0.1, 0.0]), np.array([0.0, 0.0])
    traj = gp.simulate(_spring(t_dependent=True), q0, v0, 1.0, method="rk4", dt=1e-3)
    assert traj.success


def test_impacts_and_reactions_close_the_balance() -> None:
    """The box dropped on the floor (impacts, their work in W_R) and the crane (a servo's reaction works): the
    audit passes them, their balance at round-off of the energy scale."""
    for name in ("block-on-floor", "crane"):
        scene = gp.scenes.get(name)
        traj = gp.simulate(scene.model, scene.q0, scene.v0, 2.0, lam0=scene.lam0)
        assert energy_audit.closes(scene.model) and traj.success
        assert np.abs(traj.energy_balance()).max() < 1e-6 * np.abs(traj.energy).max()
