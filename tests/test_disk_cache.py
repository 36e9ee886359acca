"""The disk cache of compiled functions (gausspp/disk_cache.py): a second process loads what the first built,
gets the same numbers, and a damaged or foreign file is rebuilt, never trusted."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import gausspp as gp
from gausspp import disk_cache

CHILD = r"""
import json, sys, numpy as np, gausspp as gp
from gausspp import disk_cache
sc = gp.scenes.get("planar-chain", N=int(sys.argv[1]), g=float(sys.argv[2]))
tr = gp.simulate(sc.model, sc.q0, sc.v0, 0.05, dt=1e-3, method="rk4", solver="direct")
print(json.dumps({"counts": disk_cache.counts, "q": tr.q[-1].tolist(), "a": tr.a[-1].tolist()}))
"""


def child(folder: Path, n: int = 5, g: float = 9.81) -> dict:
    env = {**__import__("os").environ, disk_cache.ENV: str(folder)}
    done = subprocess.run([sys.executable, "-c", CHILD, str(n), str(g)], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_second_process_loads_what_the_first_built(tmp_path: Path) -> None:
    first = child(tmp_path)
    assert first["counts"]["built"] >= 3 and first["counts"]["loaded"] == 0  # kernel, RK step, run, mapped step
    files = sorted(tmp_path.glob("*.casadi"))
    assert len(files) == first["counts"]["built"]
    second = child(tmp_path)
    assert second["counts"]["loaded"] == len(files) and second["counts"]["built"] == 0
    assert second["q"] == first["q"] and second["a"] == first["a"]  # the very same functions: the same numbers
    other = child(tmp_path, g=5.0)  # another equation (weaker gravity): its own functions
    assert other["counts"]["loaded"] == 0 and other["q"] != first["q"]


def test_a_damaged_file_is_rebuilt(tmp_path: Path) -> None:
    first = child(tmp_path)
    for path in tmp_path.glob("*.casadi"):
        path.write_bytes(b"not a casadi function")
    again = child(tmp_path)
    assert again["counts"]["loaded"] == 0 and again["counts"]["built"] == first["counts"]["built"]
    assert again["q"] == first["q"]


def test_off_means_nothing_written(tmp_path: Path, monkeypatch) -> None:
    """With the cache off, a function is built and nothing is written — looked for where the cache would write
    (the default folder under a fresh home); the control: the same call with the cache on writes a file there."""
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.setenv(disk_cache.ENV, "off")
    assert disk_cache.directory() is None
    sc = gp.scenes.get("planar-chain", N=2)
    calls = []

    def build():
        calls.append(1)
        return sc.model.kernel("direct").function

    before = dict(disk_cache.counts)
    fn = disk_cache.cached_function(sc.model, ("probe", str(tmp_path)), build)
    assert calls == [1] and fn.n_in() == 5
    assert not [p for p in home.rglob("*") if p.is_file()] and disk_cache.counts == before
    monkeypatch.delenv(disk_cache.ENV)  # the control: on, at the default folder under that home
    disk_cache.cached_function(sc.model, ("probe", str(tmp_path)), build)
    assert calls == [1, 1] and list((home / ".cache" / "gausspp").glob("*.casadi"))


def test_the_fingerprint_follows_the_equations_and_options() -> None:
    a, b = gp.scenes.get("planar-chain", N=3), gp.scenes.get("planar-chain", N=3)
    assert disk_cache.fingerprint(a.model) == disk_cache.fingerprint(b.model)  # built twice, the same equations
    heavier = gp.scenes.get("planar-chain", N=3, m=2.0)
    assert disk_cache.fingerprint(heavier.model) != disk_cache.fingerprint(a.model)
    m = a.model
    assert m.route == "dense"  # six rows: auto keeps the dense route
    other_route = gp.Model(m.mechanism, list(m.constraints), route="sparse")
    assert disk_cache.fingerprint(other_route) != disk_cache.fingerprint(m)
    assert np.isfinite(m.step(0.0, a.q0, a.v0, solver="direct").a).all()
