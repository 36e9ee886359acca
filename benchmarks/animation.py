"""What a GIF of ``plot.animate`` costs: gausspp's blitted writer against matplotlib's ``Animation.save``.

Both write the same animation (the same figure, frames and dpi) side by side in one run, alternating, best of
``--rounds``; the ratio is what counts on a shared machine. Run: ``python benchmarks/animation.py``.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from _figures import headless_pyplot

import gausspp as gp
from gausspp.studies.figures import skate_runs

CASES = {
    "four-bar (1 panel)": lambda: (
        gp.scenes.get("four-bar-redundant", t_end=1.0),
        None,
    ),
    "skate (2 panels)": lambda: (gp.scenes.get("skate"), skate_runs(t_end=10.0, samples=401)),
}


def _run(scene: gp.scenes.Scene) -> gp.Trajectory:
    times = np.linspace(0.0, scene.t_end, 201)
    return gp.simulate(scene.model, scene.q0, scene.v0, scene.t_end, record=times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    plt = headless_pyplot()
    if plt is None:
        return
    out = Path(tempfile.mkdtemp(prefix="gausspp-anim-"))
    print(f"{'case':<20} {'frames':>6} {'blitted s':>10} {'Animation.save s':>17} {'ratio':>6}")
    for name, make in CASES.items():
        scene, runs = make()
        runs = runs if runs is not None else _run(scene)
        best = {"blitted": np.inf, "matplotlib": np.inf}
        for _ in range(args.rounds):
            start = time.perf_counter()
            gp.plot.animate(scene, runs, out=out / "a.gif", frames=args.frames, fps=10, dpi=80)
            best["blitted"] = min(best["blitted"], time.perf_counter() - start)
            anim = gp.plot.animate(scene, runs, frames=args.frames, fps=10)
            start = time.perf_counter()
            anim.save(str(out / "b.gif"), writer="pillow", fps=10, dpi=80)
            best["matplotlib"] = min(best["matplotlib"], time.perf_counter() - start)
            plt.close("all")
        ratio = best["matplotlib"] / best["blitted"]
        print(f"{name:<20} {args.frames:>6} {best['blitted']:>10.2f} {best['matplotlib']:>17.2f} {ratio:>5.1f}×")


if __name__ == "__main__":
    main()
