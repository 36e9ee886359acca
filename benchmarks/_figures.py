"""Figures of the benchmark scripts: matplotlib without a display, or ``None`` (it is an optional extra)."""

from __future__ import annotations

from typing import Any


def headless_pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend, or ``None`` (said on stdout) when matplotlib is not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no figure")
        return None
    return plt
