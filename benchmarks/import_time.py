"""What ``import gausspp`` costs above its foundations, measured side by side in one run.

Each figure is the best of ``--repeats`` fresh interpreters (``python -X importtime``-free wall time of the import
statement alone, the interpreter's own start-up excluded): casadi + numpy + scipy.linalg, then ``import gausspp``.
The target: gausspp's own share at most 0.15 s. Then what the first use of a public name loads (the layers are
imported lazily, on first touch), and the packages ``import gausspp`` loads beyond the foundations, largest first
(``-X importtime``).
Run: python benchmarks/import_time.py [--repeats N]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys

FOUNDATIONS = "import casadi, numpy, scipy.linalg"
TARGET = 0.15


def best(statement: str, repeats: int) -> float:
    """The least wall time of ``statement`` over fresh interpreters, in s."""
    code = f"import time; t = time.perf_counter(); {statement}; print(time.perf_counter() - t)"
    return min(float(subprocess.check_output([sys.executable, "-c", code], text=True)) for _ in range(repeats))


def heavy(statement: str, known: str) -> list[tuple[float, str]]:
    """Packages ``statement`` loads beyond those ``known`` loads, with the import time of their modules (self
    times summed per top-level package, s), largest first."""

    def self_times(code: str) -> dict[str, float]:
        err = subprocess.run([sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True).stderr
        out: dict[str, float] = {}
        for line in err.splitlines():
            m = re.match(r"import time:\s+(\d+) \|\s+\d+ \|\s*(\S+)", line)
            if m:
                out[m.group(2)] = int(m.group(1)) / 1e6
        return out

    base = self_times(known)
    totals: dict[str, float] = {}
    for name, t in self_times(statement).items():
        if name not in base:
            package = name.split(".")[0] if not name.startswith("gausspp") else ".".join(name.split(".")[:2])
            totals[package] = totals.get(package, 0.0) + t
    return sorted(((t, name) for name, t in totals.items()), reverse=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    foundations = best(FOUNDATIONS, args.repeats)
    whole = best(f"{FOUNDATIONS}; import gausspp", args.repeats)
    print(f"casadi + numpy + scipy.linalg: {foundations:.3f} s; with import gausspp: {whole:.3f} s")
    share = whole - foundations
    print(f"gausspp's own share: {share:.3f} s (target ≤ {TARGET} s: {'met' if share <= TARGET else 'NOT met'})")
    print("\nwhat the first use of a name then loads (lazily, PEP 562), above import gausspp:")
    for name in ("Model", "simulate", "verify", "scenes", "plot", "simulate_friction"):
        first = best(f"{FOUNDATIONS}; import gausspp; gausspp.{name}", args.repeats)
        print(f"  gp.{name:18s} {first - whole:6.3f} s")
    print("\nwhat it loads beyond the foundations (s, per package; gausspp per subpackage):")
    for t, name in heavy(f"{FOUNDATIONS}; import gausspp", FOUNDATIONS)[:12]:
        print(f"  {t:7.3f}  {name}")


if __name__ == "__main__":
    main()
