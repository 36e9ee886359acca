"""The package's shape (issue 16): no import cycles, no foreign writes, plot only draws, models do not change.

The import graph and the write scan are :mod:`benchmarks/architecture.py`'s (which prints the figures); each check is
first shown to catch a deliberately broken package written to a temporary directory.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp.errors import FrozenModelError
from gausspp.workspace import workspace

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("architecture", ROOT / "benchmarks" / "architecture.py")
assert _spec is not None and _spec.loader is not None
arch = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(arch)

PACKAGE = ROOT / "gausspp"
#: What the drawing code may not import: everything that computes.
COMPUTING = (
    "gausspp.model",
    "gausspp.step",
    "gausspp.simulation",
    "gausspp.friction",
    "gausspp.scenes",
    "gausspp.verification",
    "gausspp.studies",
)


def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    root = tmp_path / "pkg"
    for name, text in {"__init__.py": "", **files}.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))
    return root


def _cycles(root: Path) -> list[set[str]]:
    return [c for c in arch.strongly_connected(arch.import_graph(root)) if len(c) > 1]


def _plot_imports(root: Path, plot: str) -> set[str]:
    graph = arch.import_graph(root)
    return {dep for mod, deps in graph.items() if mod == plot or mod.startswith(plot + ".") for dep in deps}


# -- the checks catch what they should ------------------------------------------------------------
def test_a_lazy_import_cycle_is_found(tmp_path: Path) -> None:
    root = _package(
        tmp_path,
        {
            "a.py": "from .b import g\n\ndef f():\n    return g()\n",
            "b.py": "def g():\n    from .a import f  # lazy: Python does not mind, the reader does\n    return f\n",
            "c.py": "from . import a\n",
        },
    )
    assert _cycles(root) == [{"pkg.a", "pkg.b"}]
    levels = arch.levels(arch.import_graph(root))
    assert levels["pkg.c"] == levels["pkg.a"] + 1


def test_writes_into_a_given_object_are_found(tmp_path: Path) -> None:
    root = _package(
        tmp_path,
        {
            "w.py": """
                def cache(model):
                    model.__dict__["_kernel"] = 1

                def tag(model, value):
                    model.kernel = value
                    setattr(model, "other", value)

                def fine(model):
                    own = object()
                    own.x = model  # an object this function made

                def reword(exc):
                    exc.args = ("clearer",)  # an exception re-worded before it is raised again
            """
        },
    )
    found = arch.foreign_writes(root)
    assert [f.split(" ", 1)[1] for f in found] == ["__dict__", "model.kernel =", "setattr"]


def test_drawing_that_imports_simulation_code_is_found(tmp_path: Path) -> None:
    root = _package(
        tmp_path,
        {
            "simulation/__init__.py": "",
            "simulation/run.py": "X = 1\n",
            "plot.py": "def f():\n    from .simulation.run import X\n",
        },
    )
    assert _plot_imports(root, "pkg.plot") == {"pkg.simulation.run"}


# -- the package itself ---------------------------------------------------------------------------
def test_the_package_has_no_import_cycle() -> None:
    assert _cycles(PACKAGE) == []


def test_no_module_writes_into_another_object() -> None:
    assert arch.foreign_writes(PACKAGE) == []


def test_plot_imports_no_computing_code() -> None:
    bad = {dep for dep in _plot_imports(PACKAGE, "gausspp.plot") if dep.startswith(COMPUTING)}
    assert not bad, f"gausspp.plot imports {sorted(bad)}: plot draws results it is given"


#: The layers from the bottom: each imports nothing of the layers above it (docs/architecture.md).
LAYERS = (
    "gausspp.step",
    "gausspp.model",
    "gausspp.friction",  # frictional contacts, integrated event by event; gp.simulate runs it (friction_lane.py)
    "gausspp.servo",  # index reduction integrates a model of its own; gp.simulate runs it (simulation/servo_lane.py)
    "gausspp.simulation",
    "gausspp.scenes",
    "gausspp.verification",
    "gausspp.studies",
    "gausspp.cli",
)


def _upward_imports(graph: dict[str, set[str]], layers: tuple[str, ...]) -> list[str]:
    def layer(module: str) -> int | None:
        return next((i for i, p in enumerate(layers) if module == p or module.startswith(p + ".")), None)

    return sorted(
        f"{m} -> {d}"
        for m, deps in graph.items()
        for d in deps
        if (lm := layer(m)) is not None and (ld := layer(d)) is not None and ld > lm
    )


def test_an_upward_import_is_found(tmp_path: Path) -> None:
    root = _package(
        tmp_path,
        {"low/__init__.py": "", "low/a.py": "from ..high.b import X\n", "high/__init__.py": "", "high/b.py": "X = 1\n"},
    )
    assert _upward_imports(arch.import_graph(root), ("pkg.low", "pkg.high")) == ["pkg.low.a -> pkg.high.b"]


def test_each_layer_imports_only_the_layers_below() -> None:
    """The step layer never imports the model (it reads the StepModel protocol), and so on up to the command line."""
    assert _upward_imports(arch.import_graph(PACKAGE), LAYERS) == []


def test_a_model_does_not_change() -> None:
    """Setting an attribute raises; stepping, simulating and verifying leave the model's attributes as they were."""
    scene = gp.scenes.get("pendulum")
    model = scene.model
    before = dict(vars(model))
    with pytest.raises(FrozenModelError, match="does not change after construction"):
        model.k = 5  # type: ignore[misc]
    model.step(0.0, scene.q0, scene.v0)
    model.step(0.0, scene.q0, scene.v0, solver="direct")
    traj = gp.simulate(model, scene.q0, scene.v0, 0.05, dt=0.01, method="rk4")
    gp.simulate(model, scene.q0, scene.v0, 0.05, dt=0.01, method="rk4", lane="compiled", solver="direct")
    gp.verify(model, traj)
    after = vars(model)
    assert after.keys() == before.keys()
    assert all(after[k] is before[k] for k in before)
    assert np.isfinite(traj.q).all()
    kinds = {key[0] for key in workspace(model).keys()}  # the artefacts are kept beside the model
    assert {"kernel", "compiled-run", "integral-data"} <= kinds, kinds


def test_the_namespace_holds_the_public_names_and_subpackages_only() -> None:
    """``dir(gausspp)``: ``__all__``, dunder names and gausspp's own modules — nothing leaked (``sys``,
    ``annotations``); every public error and warning of :mod:`gausspp.errors` is exported."""
    import inspect
    import pkgutil

    import gausspp
    from gausspp import errors

    own = {m.name for m in pkgutil.iter_modules(gausspp.__path__)}
    leaked = [n for n in dir(gausspp) if n not in gausspp.__all__ and not n.startswith("__") and n not in own]
    assert leaked == []
    raised = {n for n, c in inspect.getmembers(errors, inspect.isclass) if issubclass(c, Exception | Warning)}
    assert raised - set(gausspp.__all__) == set()


def test_short_module_paths_give_the_modules_themselves() -> None:
    """``import gausspp.qp`` (and the other short paths) gives the module that lives deeper, unchanged: the same
    object, its own spec (so its relative imports resolve without an ImportWarning), in a fresh interpreter."""
    code = (
        "import importlib, sys, warnings; warnings.simplefilter('error')\n"
        "import gausspp\n"
        "for short, full in gausspp._MODULES.items():\n"
        "    m = importlib.import_module('gausspp.' + short)\n"
        "    assert m is importlib.import_module(full) and m.__spec__.name == full, (short, m.__spec__.name)\n"
        "from gausspp.sweeps import grid\n"
        "gausspp.sweeps.sweep  # noqa\n"
        "print('ok')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]
