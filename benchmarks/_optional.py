"""Optional peers of the benchmarks (MuJoCo, Pinocchio): imported if installed, said and skipped if not."""

from __future__ import annotations

import importlib
from types import ModuleType


def peer(name: str) -> ModuleType | None:
    """The module, or ``None`` (and a line saying so) when it is not installed."""
    try:
        return importlib.import_module(name)
    except ImportError:
        print(f"{name} is not installed (pip install gausspp[peers]): its rows are skipped")
        return None
