"""Bad input, all of it (issue 15, item 4): every public entry point answers a project error naming the argument.

One table of bad calls across the API — the call, the expected exception class, a regex the message must match
(it names the argument and quotes the value) — and one of bad command lines (exit 2, one line on stderr). Then
property tests: fuzzed shapes, dtypes and non-finite values for ``q``, ``v``, ``t`` give a valid result or a
:class:`gausspp.GaussppError`, never another exception. Overlap with ``test_errors.py`` and ``test_cli.py`` is
avoided: the rows here are the cases those do not already hold.
"""

from __future__ import annotations

import functools
import json
import math
import re
import subprocess
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gausspp as gp
from gausspp import cli
from gausspp.cli import console
from gausspp.studies.sweeps import grid

T_END, DT = 0.01, 0.005  # two RK4 steps: a valid run costs next to nothing


# -- small models, built once -----------------------------------------------------------------------
@functools.cache
def masses() -> gp.scenes.Scene:
    """Two masses and a rod (``q = (x₁, x₂)``, ``v₂ − v₁ = 0``): the scenes' smallest model."""
    return gp.scenes.get("two-masses")


def body() -> gp.Lagrangian:
    return gp.Lagrangian(n=2, T=lambda q, v, t: 0.5 * (v[0] ** 2 + v[1] ** 2))


def rod(phi: Any, name: str = "c") -> gp.Model:
    return gp.Model(body(), gp.Constraint(phi, name=name))


def run(**kw: Any) -> gp.Trajectory:
    """``gp.simulate`` on two masses; keywords override the defaults (RK4, dt = 0.005, t_end = 0.01)."""
    s = masses()
    args: dict[str, Any] = dict(model=s.model, q0=s.q0, v0=s.v0, t_end=T_END, dt=DT, method="rk4")
    args.update(kw)
    return gp.simulate(args.pop("model"), args.pop("q0"), args.pop("v0"), args.pop("t_end"), **args)


def step(t: Any = 0.0, q: Any = None, v: Any = None, **kw: Any) -> gp.StepResult:
    s = masses()
    return s.model.step(t, s.q0 if q is None else q, s.v0 if v is None else v, **kw)


@functools.cache
def flywheel() -> gp.Model:
    """A model that carries λ as a state (inertial realization)."""
    return gp.Model(
        body(), gp.Constraint(lambda q, v, t: v[1] - v[0], name="c", realization=gp.Inertial(N=lambda q, v, t: v[0]))
    )


def path() -> dict[str, np.ndarray]:
    """The rod's exact motion on 11 samples: a valid path for gp.verify."""
    s = masses()
    assert s.exact is not None
    t = np.linspace(0.0, 1.0, 11)
    q, v = zip(*(s.exact(ti) for ti in t), strict=True)
    return {"t": t, "q": np.array(q), "v": np.array(v)}


def not_pd() -> gp.Model:
    mech = gp.MassMatrix(n=2, A=lambda q, t: [[1.0, 0.0], [0.0, -1.0]], f=lambda q, v, t: [0, 0])
    return gp.Model(mech, gp.Constraint(lambda q, v, t: v[0] + v[1], name="c"))


# -- the table ------------------------------------------------------------------------------------------
def row(name: str, call: Callable[[], Any], error: type[Exception], pattern: str) -> Any:
    return pytest.param(call, error, pattern, id=name)


ROWS = [
    # constraints and their front end (a callable of casadi symbols, affine in v)
    row(
        "constraint returns a string",
        lambda: rod(lambda q, v, t: "abc"),
        gp.SymbolicError,
        r"constraint 'c': Φ\(q, v, t\) returned 'abc'",
    ),
    row(
        "constraint returns None",
        lambda: rod(lambda q, v, t: None),
        gp.SymbolicError,
        r"constraint 'c': Φ.*returned None",
    ),
    row(
        "math.sin on a symbol",
        lambda: rod(lambda q, v, t: math.sin(q[0]) * v[0] - v[1]),
        gp.SymbolicError,
        r"constraint 'c'.*math.*casadi\.sin",
    ),
    row(
        "constraint indexes past v",
        lambda: rod(lambda q, v, t: v[5]),
        gp.SymbolicError,
        r"constraint 'c'.*could not be evaluated.*out of bounds",
    ),
    row(
        "constraint not affine in v",
        lambda: rod(lambda q, v, t: v[0] ** 2 - v[1], name="nh"),
        gp.NotAffineError,
        r"constraint 'nh': Φ\(q, v, t\) must be affine in the velocities",
    ),
    row(
        "unnamed constraint not affine",
        lambda: rod(lambda q, v, t: v[0] * v[1], name=None),
        gp.NotAffineError,
        r"unnamed Constraint \(give name=\.\.\.\)",
    ),  # type: ignore[arg-type]
    row(
        "constraint is no function",
        lambda: gp.Constraint(3),
        gp.InputError,
        r"Constraint: phi must be a function.*got 3",
    ),  # type: ignore[arg-type]
    row(
        "constraint name not a string",
        lambda: gp.Constraint(lambda q, v, t: v[0], name=5),
        gp.InputError,
        r"name must be a string, got 5",
    ),  # type: ignore[arg-type]
    row(
        "unknown realization name",
        lambda: gp.Constraint(lambda q, v, t: v[0], realization="flywheel"),
        gp.UnknownNameError,
        r"realization='flywheel' is unknown",
    ),
    row(
        "holonomic g is no function",
        lambda: gp.Holonomic("q0 - 1"),
        gp.InputError,
        r"Holonomic: g must be a function.*'q0 - 1'",
    ),  # type: ignore[arg-type]
    row(
        "holonomic g returns complex",
        lambda: gp.Model(body(), gp.Holonomic(lambda q, t: 1j, name="h")),
        gp.SymbolicError,
        r"constraint 'h': g\(q, t\) returned 1j",
    ),
    row(
        "restitution above 1",
        lambda: gp.Unilateral(lambda q, t: q[0], name="floor", restitution=2),
        gp.InputError,
        r"constraint 'floor': restitution must lie in \[0, 1\], got 2",
    ),
    row(
        "Force M is a string",
        lambda: gp.Model(body(), gp.Constraint(lambda q, v, t: v[0] - v[1], name="c", realization=gp.Force(M="abc"))),
        gp.SymbolicError,
        r"Force: M\(q, v, t\) must be a function, got 'abc'",
    ),  # type: ignore[arg-type]
    row(
        "Force bounds not a pair",
        lambda: gp.Force(M=lambda q, v, t: [1, 0], bounds="ab"),
        gp.InputError,
        r"bounds must be a pair \(lo, hi\), got 'ab'",
    ),  # type: ignore[arg-type]
    # mechanisms (front ends)
    row(
        "Lagrangian n is a string",
        lambda: gp.Lagrangian(n="2", T=lambda q, v, t: v[0] ** 2),
        gp.InputError,
        r"n must be a positive integer, got '2'",
    ),  # type: ignore[arg-type]
    row(
        "Lagrangian T is a vector",
        lambda: gp.Lagrangian(n=2, T=lambda q, v, t: v),
        gp.ShapeError,
        r"T\(q, v, t\) returned shape \(2, 1\), expected \(1, 1\)",
    ),
    row(
        "Lagrangian T with math.sqrt",
        lambda: gp.Lagrangian(n=2, T=lambda q, v, t: math.sqrt(v[0] ** 2)),
        gp.SymbolicError,
        r"T\(q, v, t\) holds a NaN constant",
    ),
    row(
        "MassMatrix A is 3-d",
        lambda: gp.MassMatrix(n=2, A=lambda q, t: np.zeros((2, 2, 2)), f=lambda q, v, t: [0, 0]),
        gp.SymbolicError,
        r"A\(q, t\) returned .*3-d array",
    ),
    row(
        "MassMatrix nq without kinematics",
        lambda: gp.MassMatrix(n=2, nq=3, A=lambda q, t: np.eye(2), f=lambda q, v, t: [0, 0]),
        gp.InputError,
        r"nq=3 differs from n=2",
    ),
    row(
        "mass matrix not positive definite",
        lambda: not_pd().step(0.0, [0.0, 0.0], [0.0, 0.0]),
        gp.NotPositiveDefiniteError,
        r"not positive definite at t=0",
    ),
    row(
        "RigidBody inertia is a string",
        lambda: gp.RigidBody(inertia="abc"),
        gp.InputError,
        r"RigidBody: inertia must be real numbers.*'abc'",
    ),
    row(
        "RigidBody inertia has NaN",
        lambda: gp.RigidBody(inertia=np.diag([1.0, np.nan, 1.0])),
        gp.NonFiniteError,
        r"RigidBody: inertia must be finite",
    ),
    row(
        "RigidBody inertia 2×2",
        lambda: gp.RigidBody(inertia=np.eye(2)),
        gp.ShapeError,
        r"RigidBody: inertia has shape \(2, 2\), expected \(3, 3\)",
    ),
    # the model
    row(
        "Model of a string",
        lambda: gp.Model("two-masses", gp.Constraint(lambda q, v, t: v[0])),
        gp.InputError,
        r"mechanism must be a Lagrangian, RigidBody or MassMatrix, got str",
    ),  # type: ignore[arg-type]
    row("Model with constraints not a list", lambda: gp.Model(body(), 3), gp.InputError, r"constraints must be"),
    row(
        "Model of a lambda",
        lambda: gp.Model(body(), [lambda q, v, t: v[0]]),
        gp.InputError,
        r"constraints must be Constraint.*got function",
    ),  # type: ignore[list-item]
    row(
        "Model margin_warn a string",
        lambda: gp.Model(body(), gp.Constraint(lambda q, v, t: v[0]), margin_warn="a"),
        gp.InputError,
        r"margin_warn must be a positive number, got 'a'",
    ),  # type: ignore[arg-type]
    row(
        "Model duplicate names",
        lambda: gp.Model(
            body(), [gp.Constraint(lambda q, v, t: v[0], name="c"), gp.Constraint(lambda q, v, t: v[1], name="c")]
        ),
        gp.InputError,
        r"names must be unique",
    ),
    # model.step
    row("step q a string", lambda: step(q="ab"), gp.InputError, r"q must be a numeric vector, got 'ab'"),
    row("step q complex", lambda: step(q=[1j, 0.0]), gp.InputError, r"q must be a numeric vector"),
    row("step q NaN", lambda: step(q=[np.nan, 1.0]), gp.NonFiniteError, r"q contains NaN or inf at t=0"),
    row("step v inf", lambda: step(v=[0.0, -np.inf]), gp.NonFiniteError, r"v contains NaN or inf"),
    row("step t a word", lambda: step(t="now"), gp.InputError, r"t must be a number, got 'now'"),
    row("step t an array", lambda: step(t=[0.0, 1.0]), gp.InputError, r"t must be a number, got \[0\.0, 1\.0\]"),
    row("step lam without λ state", lambda: step(lam=[1.0]), gp.InputError, r"lam was given but no realization"),
    row(
        "step lam NaN",
        lambda: flywheel().step(0.0, [0, 0], [0, 0], lam=[np.nan]),
        gp.NonFiniteError,
        r"lam contains NaN or inf",
    ),
    row(
        "step lam wrong size",
        lambda: flywheel().step(0.0, [0, 0], [0, 0], lam=[1.0, 2.0]),
        gp.ShapeError,
        r"lam has 2 entries, expected 1",
    ),
    row("step solver None", lambda: step(solver=None), gp.UnknownNameError, r"solver=None is unknown"),
    row(
        "step backend a number",
        lambda: step(backend=3),
        gp.UnknownNameError,
        r"QP backend must be a name or a QPBackend, got int",
    ),
    # gp.simulate
    row(
        "simulate rtol a word",
        lambda: run(method="RK45", rtol="tight"),
        gp.InputError,
        r"rtol must be a positive number .*got 'tight'",
    ),
    row("simulate dt a string", lambda: run(dt="0.01"), gp.InputError, r"dt must be a positive number .*got '0\.01'"),
    row(
        "simulate t_end 1e300 compiled",
        lambda: run(t_end=1e300, dt=0.01, method="rk4", lane="compiled", solver="direct"),
        gp.InputError,
        r"t_end - t0 = 1e\+300 .* steps, more than .* enlarge dt",
    ),
    row(
        "simulate rtol negative",
        lambda: run(method="RK45", rtol=-1),
        gp.InputError,
        r"rtol must be a positive number .*got -1",
    ),
    row(
        "simulate rtol=atol=0",
        lambda: run(method="RK45", rtol=0, atol=0),
        gp.InputError,
        r"rtol must be a positive number .*got 0",
    ),
    row(
        "simulate atol negative",
        lambda: run(method="RK45", atol=-1e-12),
        gp.InputError,
        r"atol must be a non-negative number",
    ),
    row("simulate dt zero", lambda: run(dt=0), gp.InputError, r"dt must be a positive number .*got 0"),
    row("simulate dt negative", lambda: run(dt=-0.01), gp.InputError, r"dt must be a positive number .*got -0\.01"),
    row("simulate dt NaN", lambda: run(dt=np.nan), gp.NonFiniteError, r"dt must be a positive number .*got nan"),
    row(
        "simulate fixed step without dt",
        lambda: run(dt=None),
        gp.InputError,
        r"method 'rk4' has a fixed step: give dt > 0",
    ),
    row(
        "simulate t_end before t0", lambda: run(t_end=-1.0), gp.InputError, r"need t0 < t_end, got t0=0\.0, t_end=-1\.0"
    ),
    row("simulate t_end inf", lambda: run(t_end=np.inf), gp.NonFiniteError, r"t_end must be a finite number, got inf"),
    row("simulate t_end None", lambda: run(t_end=None), gp.InputError, r"t_end must be a finite number, got None"),
    row("simulate unknown method", lambda: run(method="euler"), gp.UnknownNameError, r"method='euler' is unknown"),
    row("simulate unknown solver", lambda: run(solver="magic"), gp.UnknownNameError, r"solver='magic' is unknown"),
    row(
        "simulate unknown backend",
        lambda: run(backend="gurobix"),
        gp.UnknownNameError,
        r"QP backend 'gurobix' is unknown",
    ),
    row(
        "simulate cvodes with qp",
        lambda: run(method="cvodes", solver="qp"),
        gp.InputError,
        r"method='cvodes' needs solver='direct'",
    ),
    row(
        "simulate unknown stabilize",
        lambda: run(stabilize="bogus"),
        gp.InputError,
        r"stabilize='bogus' is not understood",
    ),
    row("simulate record zero", lambda: run(record=0), gp.InputError, r"record must be a positive integer .*got 0"),
    row(
        "simulate record a word",
        lambda: run(record="abc"),
        gp.InputError,
        r"record must be a positive integer .*got 'abc'",
    ),
    row("simulate record 2.5", lambda: run(record=2.5), gp.InputError, r"record must be a positive integer .*got 2\.5"),
    row(
        "simulate record empty",
        lambda: run(record=[]),
        gp.ShapeError,
        r"record must be .* 1-D array of times, got shape \(0,\)",
    ),
    row(
        "simulate record 2-d",
        lambda: run(record=[[0.0, 0.005]]),
        gp.ShapeError,
        r"record must be .* 1-D array of times, got shape \(1, 2\)",
    ),
    row(
        "simulate record beyond t_end",
        lambda: run(record=[0.0, 5.0]),
        gp.InputError,
        r"record times must lie within \[t0, t_end\]",
    ),
    row("simulate record NaN", lambda: run(record=[np.nan]), gp.NonFiniteError, r"record must be finite"),
    row("simulate throw a word", lambda: run(throw="yes"), gp.InputError, r"throw must be True or False, got 'yes'"),
    row(
        "simulate constraint_tol negative",
        lambda: run(constraint_tol=-1),
        gp.InputError,
        r"constraint_tol must be a non-negative number",
    ),
    row(
        "simulate max_events zero",
        lambda: run(max_events=0),
        gp.InputError,
        r"max_events must be a positive integer, got 0",
    ),
    row(
        "simulate model a name",
        lambda: run(model="two-masses"),
        gp.InputError,
        r"model must be a gp\.Model .*got 'two-masses'",
    ),
    row(
        "simulate q0 off the constraint",
        lambda: run(v0=[0.0, 1.0]),
        gp.InitialDataError,
        r"off the constraint 'rod' at t=0",
    ),
    row("simulate q0 wrong shape", lambda: run(q0=[0.0, 1.0, 2.0]), gp.ShapeError, r"q has 3 entries, expected 2"),
    # gp.verify
    row(
        "verify a string",
        lambda: gp.verify(masses().model, "abc"),
        gp.InputError,
        r"trajectory must be a gp\.Trajectory .*got str 'abc' without t, q, v",
    ),
    row(
        "verify without v",
        lambda: gp.verify(masses().model, {k: x for k, x in path().items() if k != "v"}),
        gp.InputError,
        r"without v$",
    ),
    row(
        "verify q of words",
        lambda: gp.verify(masses().model, {**path(), "q": "xy"}),
        gp.InputError,
        r"trajectory: q must be real numbers",
    ),
    row(
        "verify a model name",
        lambda: gp.verify("two-masses", path()),
        gp.InputError,
        r"model must be a gp\.Model, got 'two-masses'",
    ),  # type: ignore[arg-type]
    row(
        "verify unknown method",
        lambda: gp.verify(masses().model, path(), method="newton"),
        gp.UnknownNameError,
        r"method='newton' is unknown",
    ),
    row(
        "verify nodes a word",
        lambda: gp.verify(masses().model, path(), nodes="abc"),
        gp.InputError,
        r"nodes must be a positive integer .*got 'abc'",
    ),  # type: ignore[arg-type]
    row(
        "verify window a word",
        lambda: gp.verify(masses().model, path(), window="ab"),
        gp.InputError,
        r"window must be real numbers",
    ),  # type: ignore[arg-type]
    row(
        "verify window of three",
        lambda: gp.verify(masses().model, path(), window=(0.0, 0.5, 1.0)),
        gp.ShapeError,
        r"window must be two times",
    ),  # type: ignore[arg-type]
    row(
        "verify unknown metric",
        lambda: gp.verify(masses().model, path(), metric="euclid"),
        gp.UnknownNameError,
        r"metric='euclid' is unknown",
    ),
    row(
        "verify a NaN sample",
        lambda: gp.verify(masses().model, {**path(), "v": np.where(np.arange(11)[:, None] == 3, np.nan, path()["v"])}),
        gp.NonFiniteError,
        r"sample 3 \(t=0\.3\) is not finite",
    ),
    # gp.scenes.get: every parameter checked by type in one place
    row(
        "scene F='two'",
        lambda: gp.scenes.get("two-masses", F="two"),
        gp.InputError,
        r"scene 'two-masses': F must be a finite number, got 'two'",
    ),
    row(
        "scene F NaN",
        lambda: gp.scenes.get("two-masses", F=np.nan),
        gp.NonFiniteError,
        r"F must be a finite number, got nan",
    ),
    row(
        "scene F a vector",
        lambda: gp.scenes.get("two-masses", F=[1.0, 2.0]),
        gp.ShapeError,
        r"F must be a finite number, got \[1\.0, 2\.0\] \(one value, not an array of shape \(2,\)\)",
    ),
    row(
        "scene m1 True",
        lambda: gp.scenes.get("two-masses", m1=True),
        gp.InputError,
        r"m1 must be a finite number, got True",
    ),
    row(
        "scene unknown parameter",
        lambda: gp.scenes.get("two-masses", mass=2.0),
        gp.UnknownNameError,
        r"scene 'two-masses' has no parameter 'mass'; its parameters: m1, m2, F",
    ),
    row(
        "scene n=2.5",
        lambda: gp.scenes.get("stiff-chain", n=2.5),
        gp.InputError,
        r"scene 'stiff-chain': n must be an integer, got 2\.5",
    ),
    row(
        "scene realization a number",
        lambda: gp.scenes.get("two-masses", realization=3),
        gp.InputError,
        r"realization must be a string, got 3",
    ),
    row(
        "scene redundant a word",
        lambda: gp.scenes.get("four-bar-redundant", redundant="yes"),
        gp.InputError,
        r"redundant must be True or False, got 'yes'",
    ),
    row(
        "scene inertia a word",
        lambda: gp.scenes.get("gyrostat", inertia="abc"),
        gp.InputError,
        r"gyrostat: inertia must be real numbers",
    ),
    row(
        "scene M complex",
        lambda: gp.scenes.get("mixed-rate", M=(1j, 0.0)),
        gp.InputError,
        r"mixed: M must be real numbers",
    ),
    row(
        "scene law given twice",
        lambda: gp.scenes.get("mixed-rate", law="rate"),
        gp.UnknownNameError,
        r"scene 'mixed-rate' has no parameter 'law'",
    ),
    row(
        "scene t_end negative",
        lambda: gp.scenes.get("pendulum", t_end=-1.0),
        gp.InputError,
        r"scene 'pendulum': t_end must be positive, got -1\.0",
    ),
    row(
        "scene tau inf",
        lambda: gp.scenes.get("saturated-crane", tau=np.inf),
        gp.NonFiniteError,
        r"tau must be a finite number, got inf",
    ),
    row(
        "scene name a number",
        lambda: gp.scenes.get(3),
        gp.UnknownNameError,
        r"scene 3 is unknown; available: \['two-masses'",
    ),  # type: ignore[arg-type]
    row(
        "scene parameters of nothing",
        lambda: gp.scenes.parameters("nosuch"),
        gp.UnknownNameError,
        r"scene 'nosuch' is unknown",
    ),
    # gp.sweep
    row(
        "sweep out a directory",
        lambda: gp.sweep(
            gp.sweeps.realizability_task, grid(lon=[0.0], lat=[0.0]), executor="serial", out="/", progress=False
        ),
        gp.sweeps.SweepError,
        r"out='/': '/' is a directory; give a file name",
    ),
    row(
        "sweep executor a number",
        lambda: gp.sweep(gp.sweeps.realizability_task, grid(lon=[0.0], lat=[0.0]), executor=3),
        gp.InputError,
        r"executor must be None, 'serial'.*got int",
    ),
    # issue 28: the second list
    row(
        "Lagrangian of a billion coordinates",
        lambda: gp.Lagrangian(n=10**9, T=lambda q, v, t: 0),
        gp.InputError,
        r"n=1000000000 coordinates: .*at most 10000",
    ),
    row("Vakonomic lam0 a string", lambda: gp.Vakonomic(lam0="x"), gp.InputError, r"lam0 .*'x'"),
    row("Baumgarte alpha a string", lambda: gp.Baumgarte("a"), gp.InputError, r"Baumgarte: alpha .*'a'"),
    row("Baumgarte beta NaN", lambda: gp.Baumgarte(1.0, math.nan), gp.InputError, r"Baumgarte: beta .*nan"),
    row("Baumgarte.critical a string", lambda: gp.Baumgarte.critical("a"), gp.InputError, r"tau .*'a'"),
    row(
        "crosscheck of a scene's name",
        lambda: gp.crosscheck("two-masses", 0.0, masses().q0, masses().v0),
        gp.InputError,
        r"crosscheck: model must be a gp.Model .*'two-masses'",
    ),
    row(
        "crosscheck tolerance negative",
        lambda: gp.crosscheck(masses().model, 0.0, masses().q0, masses().v0, tolerance=-1),
        gp.InputError,
        r"tolerance must be a positive number.*-1",
    ),
    row("replay of a string", lambda: gp.replay(masses().model, "abc"), gp.InputError, r"replay: traj .*'abc'"),
    row("plot.trajectory of a string", lambda: gp.plot.trajectory("abc"), gp.InputError, r"trajectories: .*'abc'"),
    row(
        "Force bounds crossed",
        lambda: gp.Force(lambda q, v, t: q, bounds=(1, -1)),
        gp.InputError,
        r"Force: a lower bound exceeds its upper bound: bounds=\(1, -1\)",
    ),
    row("Force bounds a string", lambda: gp.Force(lambda q, v, t: q, bounds=("a", 1)), gp.InputError, r"bounds .*'a'"),
    row("grid axis a string", lambda: grid(realization="servo"), gp.InputError, r"grid axis realization='servo'"),
    row(
        "verify constraint_tol negative",
        lambda: gp.verify(masses().model, run(v0=[0.5, 0.5]), constraint_tol=-1),
        gp.InputError,
        r"constraint_tol must be a non-negative number.*-1",
    ),
    row("from_urdf of no file", lambda: gp.from_urdf("/no/such.urdf"), gp.InputError, r"'/no/such.urdf': no such file"),
    row("model.step refine a string", lambda: step(refine="no"), gp.InputError, r"refine must be True or False.*'no'"),
    row(
        "Model codegen a string",
        lambda: gp.Model(body(), gp.Constraint(lambda q, v, t: v[1] - v[0]), codegen="yes"),
        gp.InputError,
        r"codegen must be True or False.*'yes'",
    ),
    row(
        "sweep progress a string",
        lambda: gp.sweep(gp.sweeps.realizability_task, [], executor="serial", progress="no"),
        gp.InputError,
        r"progress must be True or False.*'no'",
    ),
    row("simulate drift_tol zero", lambda: run(drift_tol=0), gp.InputError, r"drift_tol must be a positive number.*0"),
    row("simulate dt longer than the run", lambda: run(dt=1.0), gp.InputError, r"dt=1 is longer than the run"),
    row(
        "simulate record times backwards",
        lambda: run(method="RK45", dt=None, record=[0.005, 0.0]),
        gp.InputError,
        r"record times must increase.*record\[0\] = 0.005",
    ),
]


@pytest.mark.parametrize(("call", "error", "pattern"), ROWS)
def test_bad_input_is_a_named_project_error(call: Callable[[], Any], error: type[Exception], pattern: str) -> None:
    assert issubclass(error, gp.GaussppError)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)  # casadi's notice about numpy functions on its values
        with pytest.raises(error, match=pattern) as info:
            call()
    assert isinstance(info.value, gp.GaussppError)
    assert "\n" not in str(info.value)  # one line, nothing pasted from a C++ backtrace


def test_the_table_is_large() -> None:
    assert len(ROWS) >= 40


# -- the command line --------------------------------------------------------------------------------
CLI_ROWS = [
    (["--bogus-flag"], "unrecognized arguments: --bogus-flag"),
    (["--bogus-flag", "run"], "unrecognized arguments: --bogus-flag"),
    (["run", "--bogus-flag"], "unrecognized arguments: --bogus-flag"),
    (["verify", "two-masses", "--expect", "motion", "--frobnicate=3"], "unrecognized arguments: --frobnicate=3"),
    (["scenes", "two-masses", "-z"], "unrecognized arguments: -z"),
    (["run", "two-masses", "--rtol", "tight"], "--rtol"),
    (["run", "two-masses", "--param", "F=two"], "F=two"),
    (["run", "two-masses", "--param", "F=(1, 2)"], "F must be a number"),
    (["sweep", "realizability", "--workers", "0"], "--workers"),
    (["sweep", "work-precision", "--resolution", "2"], "--resolution applies to `gausspp sweep realizability` only"),
]


@pytest.mark.parametrize(("argv", "fragment"), CLI_ROWS, ids=[" ".join(r[0]) for r in CLI_ROWS])
def test_bad_command_line_is_one_usage_line(argv: list[str], fragment: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gausspp: error: ") and fragment in lines[0], captured.err
    assert captured.out == ""


def test_bogus_flag_by_the_real_entry_point() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "gausspp.cli", "--bogus-flag"], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 2
    assert result.stderr.strip() == "gausspp: error: unrecognized arguments: --bogus-flag (see 'gausspp --help')"


def test_an_abbreviated_or_attached_option_is_still_known(capsys: pytest.CaptureFixture[str]) -> None:
    # argparse accepts --para for --param and -pKEY=VALUE: the check for unknown options must too
    assert cli.main(["--qui", "run", "two-masses", "--para", "m1=2", "-pF=1", "--t-end", "0.01"]) == 0
    assert "two-masses (m1=2.0, F=1.0)" in capsys.readouterr().out


# -- a long run announces itself, before the wait ----------------------------------------------------------
def test_a_long_run_warns_up_front_with_the_step_count() -> None:
    # 1e7 RK4 steps: the warning comes from the argument checks, the run then stops at once on initial data
    # off the constraint — nothing is integrated
    s = masses()
    with pytest.warns(gp.LongRunWarning, match=r"1e\+07 steps \(method 'rk4'\).*take long"):
        with pytest.raises(gp.InitialDataError):
            gp.simulate(s.model, s.q0, [0.0, 1.0], 1.0, dt=1e-7)
    with warnings.catch_warnings():
        warnings.simplefilter("error", gp.LongRunWarning)  # a short run is silent
        run()


def test_a_long_adaptive_run_warns_with_a_lower_bound() -> None:
    s = masses()
    with pytest.warns(gp.LongRunWarning, match=r"at least 2e\+06 steps"):
        with pytest.raises(gp.InitialDataError):
            gp.simulate(s.model, s.q0, [0.0, 1.0], 2.0, dt=1e-6, method="DOP853", record=[0.0, 2.0])


def test_states_that_do_not_fit_in_memory_are_refused() -> None:
    # the compiled RK keeps every step: 1e8 states of 6 numbers are 4.5 GiB
    with pytest.raises(gp.InputError, match=r"would keep 1e\+08 states .*GiB"):
        run(t_end=1e4, dt=1e-4, method="rk4", lane="compiled", solver="direct")


def test_the_command_line_shows_the_long_run_warning_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    shown: list[str] = []
    monkeypatch.setattr(console, "print", lambda *a, **k: shown.append(" ".join(map(str, a))), raising=False)
    with console.warnings_as_lines():
        warnings.warn("many steps", gp.LongRunWarning, stacklevel=1)
        assert shown == ["gausspp: warning: LongRunWarning: many steps"]  # before the block ends
        warnings.warn("small margin", gp.RealizabilityWarning, stacklevel=1)
        assert len(shown) == 1
    assert shown[1] == "gausspp: warning: RealizabilityWarning: small margin"


# -- a damaged sweep log ---------------------------------------------------------------------------------
CALLS: list[int] = []


def counting_task(p: dict[str, Any]) -> dict[str, float]:
    CALLS.append(int(p["i"]))
    return {"y": 2.0 * p["i"]}


def test_a_damaged_line_of_a_sweep_log_warns_with_file_and_line(tmp_path: Path) -> None:
    out = tmp_path / "log.jsonl"
    params = grid(i=range(5))
    first = gp.sweep(counting_task, params, executor="serial", out=out, progress=False)
    lines = out.read_text().splitlines(keepends=True)  # the task's name, then the records of tasks 0…4
    damaged = next(n for n, line in enumerate(lines) if json.loads(line).get("index") == 2)
    lines[damaged] = "{this is not json\n"
    out.write_text("".join(lines) + '{"index": 4, "par')  # and a record a kill cut short: silent
    CALLS.clear()
    with pytest.warns(gp.SweepLogWarning) as caught:
        again = gp.sweep(counting_task, params, executor="serial", out=out, progress=False)
    assert len(caught) == 1
    assert f"out={str(out)!r} line {damaged + 1} is not a record" in str(caught[0].message)
    assert CALLS == [2] and again.results == first.results  # only the damaged task ran again
    assert out.read_text().endswith("\n") and '"par\n' not in out.read_text()  # the partial record was cut off


# -- property tests: fuzzed q, v, t never give a foreign exception -------------------------------------------
FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)
SCALARS = st.one_of(
    FLOATS,
    st.integers(min_value=-(10**30), max_value=10**30),
    st.booleans(),
    st.none(),
    st.text(max_size=4),
    st.complex_numbers(max_magnitude=10.0),
    st.just(object()),
)
ARRAYS = st.one_of(
    st.lists(SCALARS, max_size=4),
    st.lists(FLOATS, min_size=2, max_size=2),  # the right size, maybe not finite
    st.lists(st.lists(FLOATS, max_size=3), max_size=3),  # nested, maybe ragged
    st.sampled_from(  # every dtype, and shapes that are not a vector
        [
            np.array([1.0, 2.0]),
            np.array([1, 2], dtype=np.int64),
            np.array([True, False]),
            np.array([1 + 1j, 0]),
            np.array([object(), 1.0], dtype=object),
            np.array(["a", "b"]),
            np.zeros((2, 2)),
            np.zeros(0),
            np.array(1.0),
        ]
    ),
    st.builds(lambda x: np.full((2, 1), x), FLOATS),  # a column
)
STATES = st.one_of(SCALARS, ARRAYS)
FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _valid_or_project_error(call: Callable[[], Any], kind: type) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # realizability or casadi notices: not what is checked here
        try:
            result = call()
        except gp.GaussppError:
            return
    assert isinstance(result, kind)


@FUZZ
@given(t=STATES, q=STATES, v=STATES)
def test_fuzzed_step_gives_a_result_or_a_project_error(t: Any, q: Any, v: Any) -> None:
    model = masses().model
    _valid_or_project_error(lambda: model.step(t, q, v), gp.StepResult)


@FUZZ
@given(q0=STATES, v0=STATES)
def test_fuzzed_initial_state_gives_a_trajectory_or_a_project_error(q0: Any, v0: Any) -> None:
    model = masses().model
    _valid_or_project_error(lambda: gp.simulate(model, q0, v0, T_END, dt=DT, method="rk4"), gp.Trajectory)


@FUZZ
@given(t0=STATES, t_end=STATES, dt=STATES)
def test_fuzzed_times_give_a_project_error_never_a_foreign_one(t0: Any, t_end: Any, dt: Any) -> None:
    # the initial velocity is off the rod, so a run whose times pass the checks stops before its first step
    # (arbitrary t_end/dt would otherwise mean arbitrarily long runs)
    s = masses()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(gp.GaussppError):
            gp.simulate(s.model, s.q0, [0.0, 1.0], t_end, t0=t0, dt=dt, method="rk4")


@FUZZ
@given(rtol=STATES, atol=STATES, record=STATES)
def test_fuzzed_tolerances_and_record_give_a_trajectory_or_a_project_error(rtol: Any, atol: Any, record: Any) -> None:
    s = masses()
    _valid_or_project_error(
        lambda: gp.simulate(s.model, s.q0, s.v0, T_END, method="RK45", rtol=rtol, atol=atol, record=record),
        gp.Trajectory,
    )


def test_a_valid_state_still_steps() -> None:
    # the fuzzing above must not be vacuous: good data give a result with the rod's acceleration F/(m1 + m2)
    result = step(0.0, np.array([0.0, 1.0]), np.array([0.5, 0.5]))
    np.testing.assert_allclose(result.a, [0.5, 0.5], rtol=1e-12)
    traj = run(v0=[0.5, 0.5])
    assert traj.success and traj.t[-1] == pytest.approx(T_END)


def test_from_urdf_names_a_file_that_is_no_urdf(tmp_path: Path) -> None:
    broken, page = tmp_path / "broken.urdf", tmp_path / "page.urdf"
    broken.write_text("<robot><link name='a'>")
    page.write_text("<html></html>")
    with pytest.raises(gp.InputError, match=r"broken.urdf' is not well-formed XML"):
        gp.from_urdf(str(broken))
    with pytest.raises(gp.InputError, match=r"page.urdf' is not a URDF file \(its root element is <html>"):
        gp.from_urdf(str(page))


def _always_fails(p: dict) -> dict:
    raise ValueError(f"no result for x={p['x']}")


def test_a_sweep_whose_every_task_fails_says_so() -> None:
    with pytest.warns(gp.SweepWarning, match=r"every one of the 2 tasks failed \(the first: .*no result for x=1"):
        result = gp.sweep(_always_fails, grid(x=[1, 2]), executor="serial", progress=False)
    assert len(result.errors) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the control: one success, no warning
        gp.sweep(_square_or_fail, grid(x=[1, 2]), executor="serial", progress=False)


def _square_or_fail(p: dict) -> dict:
    if p["x"] == 2:
        raise ValueError("two")
    return {"y": p["x"] ** 2}


def test_an_adaptive_run_of_days_is_refused_from_its_first_steps_keeping_them() -> None:
    """No dt, t_end = 1e9 s: the forecast from the first accepted steps refuses it (measured: 5e10 steps) at once,
    with what was computed; a forecast of hours is announced (LongRunWarning) and goes on."""
    s = gp.scenes.get("pendulum")
    traj = gp.simulate(s.model, s.q0, s.v0, 1e9, throw=False)
    assert traj.status == "failed" and isinstance(traj.failure, gp.IntegrationError)
    assert re.search(r"to t_end=1e\+09 that is about [0-9.e+]+ steps, more than the 1e\+10", traj.message)
    assert len(traj) > 100 and traj.t[-1] > 0  # the steps taken are kept
    from gausspp.simulation import inputs

    with pytest.warns(gp.LongRunWarning, match=r"about 5e\+06 steps: this run will take long"):
        inputs.check_forecast("DOP853", 0.0, 5e4, 2.0, 200, 8, 200)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the control: a short run is neither refused nor announced
        inputs.check_forecast("DOP853", 0.0, 5.0, 2.0, 200, 8, 200)


def test_a_urdf_link_of_negative_mass_and_string_gravity_are_refused(tmp_path: Path) -> None:
    robot = tmp_path / "arm.urdf"
    robot.write_text(
        "<robot name='arm'><link name='base'/><link name='upper'><inertial><mass value='-1.0'/>"
        "<inertia ixx='1' iyy='1' izz='1' ixy='0' ixz='0' iyz='0'/></inertial></link>"
        "<joint name='shoulder' type='revolute'><parent link='base'/><child link='upper'/><axis xyz='0 0 1'/>"
        "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>"
    )
    with pytest.raises(gp.InputError, match=r"link 'upper' of .*arm.urdf' has mass '-1.0'"):
        gp.from_urdf(str(robot))
    robot.write_text(robot.read_text().replace("-1.0", "2.0"))
    with pytest.raises(gp.InputError, match=r"g must be a finite number .*'9.81x'"):
        gp.from_urdf(str(robot), g="9.81x")  # type: ignore[arg-type]


def test_an_inertia_no_body_has_is_refused() -> None:
    with pytest.raises(gp.InputError, match=r"violate the triangle inequality"):
        gp.RigidBody(np.diag([1.0, 1.0, 3.0]))
    gp.RigidBody(np.diag([1.0, 1.0, 2.0]))  # the control: a thin disc (I₃ = I₁ + I₂) is a body


def test_from_sympy_names_a_parameter_that_is_no_number() -> None:
    sympy = pytest.importorskip("sympy")
    me = pytest.importorskip("sympy.physics.mechanics")
    q, u = me.dynamicsymbols("q u")
    m, g = sympy.symbols("m g")
    frame = me.ReferenceFrame("N")
    point = me.Point("O")
    point.set_vel(frame, 0)
    particle_point = point.locatenew("P", q * frame.x)
    particle_point.set_vel(frame, u * frame.x)
    kane = me.KanesMethod(frame, q_ind=[q], u_ind=[u], kd_eqs=[q.diff() - u])
    kane.kanes_equations([me.Particle("p", particle_point, m)], [(particle_point, -m * g * frame.x)])
    with pytest.raises(gp.InputError, match=r"parameter m must be a finite number, got 'one'"):
        gp.from_sympy(kane, parameters={m: "one", g: 9.81})


def test_dependent_ideal_rows_are_told_apart_from_dependent_reaction_directions() -> None:
    """Ideal rows that lose rank (a redundant loop equation, or a linkage's bars in line) get advice about rows and
    singular positions; two forces along one direction keeping independent rows get the realizations' advice."""
    redundant = gp.scenes.get("four-bar-redundant")
    with pytest.raises(gp.RealizabilityError, match=r"not together .*rows are dependent here .*solver='qp' steps them"):
        redundant.model.step(0.0, redundant.q0, redundant.v0, solver="direct")
    push = gp.Force(lambda q, v, t: ca.DM([[1.0, 1.0]]))
    model = gp.Model(
        body(),
        [
            gp.Constraint(lambda q, v, t: v[0] - 1.0, name="a", realization=push),
            gp.Constraint(lambda q, v, t: v[1], name="b", realization=push),
        ],
    )
    with pytest.raises(gp.RealizabilityError, match=r"not together .*change one of the realizations"):
        model.step(0.0, np.zeros(2), np.array([1.0, 0.0]), solver="direct")
