"""Mutation check of gausspp's core: does the test suite catch a wrong formula where it matters?

Each mutant below is a hand-written slip in one core spot — a sign, a factor, a dropped term, a check that
never fires — given as an exact ``old`` snippet of a file under ``gausspp/`` and its ``new`` replacement,
with the tests that *should* catch it. The script first takes one snapshot of the repository's ``gausspp/``,
``tests/`` and ``pyproject.toml`` (the working tree as it is, uncommitted edits included; never modified). For
each mutant it copies that snapshot into a fresh temporary directory, applies the mutation there, and runs
``python -m pytest -x -q -p no:cacheprovider <its tests>`` in that copy, with ``PYTHONPATH`` pointing at it,
and ``GAUSSPP_CACHE_DIR`` and ``TMPDIR`` at directories of its own (so that no compiled function cached from
the unmutated code is loaded — the cache keys on gausspp's source anyway — and nothing is written outside
the copy). The copy is removed afterwards (``--keep`` keeps it, ``--logs DIR`` keeps pytest's output).

Results: **killed** (pytest failed a test), **SURVIVED** (the tests passed: they do not see the slip),
**broken** (the mutant did not get as far as running tests: a collection or import error, a usage error),
**timeout**. Every snippet must occur exactly once in its file: after a refactor that moves the code the
script stops with an error naming the mutant instead of silently checking nothing.

Before the mutants, the unmutated copy runs the union of their tests (``--no-baseline`` skips it): a test
that fails without any mutation kills nothing, and a mutant "killed" by such a test is reported as
``baseline-fails``.

Run it (from any directory: the repository is the one that holds this script)::

    python benchmarks/mutation_check.py                 # every mutant, one at a time
    python benchmarks/mutation_check.py --list          # what the mutants are
    python benchmarks/mutation_check.py --only dense-refine-r0,sparse-refine-r0 --jobs 2 --logs /tmp/mutants
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: What each sandbox holds: the package, its tests and the pytest configuration (and a root conftest if any).
COPIED = ("gausspp", "tests", "pyproject.toml", "conftest.py")
TIMEOUT = 15 * 60.0


@dataclass(frozen=True)
class Mutant:
    """One slip: replace ``old`` (exactly once in ``gausspp/<file>``) by ``new``; ``tests`` should catch it."""

    id: str
    description: str
    file: str
    old: str
    new: str
    tests: tuple[str, ...]


@dataclass(frozen=True)
class Outcome:
    """What pytest said about one mutant (or the baseline)."""

    result: str  # killed / SURVIVED / broken / timeout / baseline-fails
    seconds: float
    detail: str  # the first failing test, or why the mutant is broken


MUTANTS: tuple[Mutant, ...] = (
    # -- the compiled equality step: direct (multiplier) formula, QP, refinement, reduction --------------------
    Mutant(
        "direct-sign",
        "dense direct step: whitened reaction z = -Ŝ⁻¹ r̂ (sign slip in the multiplier solve)",
        "step/equality/direct.py",
        "return ca.solve(red.S_hat, red.rhs_hat)",
        "return -ca.solve(red.S_hat, red.rhs_hat)",
        ("tests/test_crosscheck.py", "tests/test_gauss_principle.py", "tests/test_two_masses.py"),
    ),
    Mutant(
        "sparse-direct-sign",
        "sparse direct step: u = -S⁻¹ rhs (sign slip in the sparse multiplier solve)",
        "step/equality/kernel.py",
        "sparse.sparse_outputs(p, sred, sred.solve_S(sred.rhs), None, refines)",
        "sparse.sparse_outputs(p, sred, -sred.solve_S(sred.rhs), None, refines)",
        ("tests/test_sparse_route.py",),
    ),
    Mutant(
        "compiled-qp-half",
        "compiled QP step: half the QP's whitened reaction, refinement off",
        "step/equality/qp_parts.py",
        "results = outputs(p_in, red_in, x, rows_in * y, refines)",
        "results = outputs(p_in, red_in, 0.5 * x, rows_in * y, False)",
        ("tests/test_gauss_principle.py", "tests/test_crosscheck.py", "tests/test_checked_step.py"),
    ),
    Mutant(
        "general-qp-half",
        "general Gauss QP (Python step): half the reaction w goes into the acceleration",
        "step/general/solve.py",
        "reaction = w * s.unit",
        "reaction = 0.5 * w * s.unit",
        ("tests/test_general_qp.py", "tests/test_contact.py", "tests/test_redundancy.py"),
    ),
    Mutant(
        "dense-refine-r0",
        "dense refinement drops r₀: r1 = f − (A a − D u)",
        "step/equality/expressions.py",
        "r1 = p.f + p.r0 - (p.A @ a - p.D @ u)",
        "r1 = p.f - (p.A @ a - p.D @ u)",
        (
            "tests/test_gauss_principle.py",
            "tests/test_crosscheck.py",
            "tests/test_checked_step.py",
            "tests/test_random_mechanisms.py",
        ),
    ),
    Mutant(
        "sparse-refine-r0",
        "sparse refinement drops r₀: r1 = f − (A a − D u) in sparse_outputs",
        "step/equality/sparse.py",
        "r1 = p.f + p.r0 - (p.A @ a - p.D @ u)",
        "r1 = p.f - (p.A @ a - p.D @ u)",
        ("tests/test_sparse_route.py", "tests/test_general_sparse.py"),
    ),
    Mutant(
        "sparse-rhs-x1.1",
        "shared sparse reduction: right-hand side 1.1·(φ − J a₀) (sparse_reduce)",
        "step/equality/sparse.py",
        "rhs = p.phi - p.J @ a0",
        "rhs = 1.1 * (p.phi - p.J @ a0)",
        ("tests/test_sparse_route.py", "tests/test_general_sparse.py"),
    ),
    Mutant(
        "dense-rhs-x1.1",
        "dense reduction: right-hand side 1.1·(φ − J a₀) (expressions.reduce)",
        "step/equality/expressions.py",
        "rhs_hat = ca.solve(RJ.T, p.phi - p.J @ a0)",
        "rhs_hat = ca.solve(RJ.T, 1.1 * (p.phi - p.J @ a0))",
        ("tests/test_two_masses.py", "tests/test_gauss_principle.py", "tests/test_crosscheck.py"),
    ),
    # -- verification by the integral principle (23) -------------------------------------------------------------
    Mutant(
        "integral-qp-gap-half",
        "integral principle: the discrete QP's gap halved (solve_qp returns value/T, not 2·value/T)",
        "verification/discrete.py",
        "return 2.0 * value / (d.t[-1] - d.t[0]), eta, lam",
        "return value / (d.t[-1] - d.t[0]), eta, lam",
        ("tests/test_integral.py",),
    ),
    Mutant(
        "judge-gap-half",
        "integral principle: the judged gap halved (integral.judge)",
        "verification/integral.py",
        "gap = max(0.0, -difference)",
        "gap = max(0.0, -0.5 * difference)",
        ("tests/test_integral.py", "tests/test_verify_every_scene.py"),
    ),
    Mutant(
        "verdict-floor-1e-3",
        "verdict: a relative gap up to 1e-3 counts as a motion (GAP_FLOOR 1e-8 → 1e-3)",
        "verification/integral.py",
        "GAP_FLOOR = 1e-8",
        "GAP_FLOOR = 1e-3",
        ("tests/test_integral.py", "tests/test_verify_every_scene.py"),
    ),
    # -- index reduction, the disk cache, the margin, the audits -------------------------------------------------
    Mutant(
        "servo-poles-positive",
        "index reduction: feedback polynomial (s − p)ʳ, poles at +p (unstable)",
        "servo/index_reduction.py",
        "comb(r, j) * p ** (r - j) * chain[j]",
        "comb(r, j) * (-p) ** (r - j) * chain[j]",
        ("tests/test_index_reduction.py",),
    ),
    Mutant(
        "cache-off-directory",
        "disk cache: GAUSSPP_CACHE_DIR=off gives a directory in the temp folder instead of None",
        "disk_cache.py",
        'if value.lower() in ("off", "0", "none", "false"):\n        return None',
        'if value.lower() in ("off", "0", "none", "false"):\n'
        '        return Path(tempfile.gettempdir()) / "gausspp-off"',
        ("tests/test_disk_cache.py", "tests/test_crosscheck.py"),
    ),
    Mutant(
        "cache-off-still-writes",
        "disk cache: switched off (directory() None), cached_function still stores files in the temp folder",
        "disk_cache.py",
        "if folder is None:\n        return build()",
        'if folder is None:\n        folder = Path(tempfile.gettempdir()) / "gausspp-off"',
        ("tests/test_disk_cache.py", "tests/test_crosscheck.py"),
    ),
    Mutant(
        "margin-largest",
        "realizability margin: the largest cosine instead of the smallest (margin_of)",
        "step/realizability.py",
        "return float(cos[-1])",
        "return float(cos[0])",
        (
            "tests/test_margin_in_integration.py",
            "tests/test_checked_step.py",
            "tests/test_sparse_route.py",
            "tests/test_scene_skate_crane.py",
        ),
    ),
    Mutant(
        "residual-audit-never-fails",
        "residual audit: never reports a sample off the constraint",
        "simulation/residual_audit.py",
        "if not samples.size:",
        "if True:",
        ("tests/test_residual_audit.py",),
    ),
    Mutant(
        "energy-audit-never-fails",
        "energy audit: never reports a broken energy balance",
        "simulation/energy_audit.py",
        "if n < 2 or not closes(model):",
        "if True:",
        ("tests/test_energy_audit.py",),
    ),
    Mutant(
        "energy-balance-reaction-sign",
        "energy audit: the reactions' work W_R added instead of subtracted in the balance",
        "simulation/energy_audit.py",
        "balance = (energy[:n] - energy[0]) - (y[:n, -2] - y[0, -2])",
        "balance = (energy[:n] - energy[0]) + (y[:n, -2] - y[0, -2])",
        ("tests/test_energy_audit.py",),
    ),
    # -- impacts, singular positions, drift control --------------------------------------------------------------
    Mutant(
        "impact-restitution-half",
        "impact law: restitution target ġ⁺ ≥ −(e/2)·ġ⁻ instead of −e·ġ⁻",
        "step/impact.py",
        "target = -e * np.minimum(d.gdotc[closed], 0.0)",
        "target = -0.5 * e * np.minimum(d.gdotc[closed], 0.0)",
        ("tests/test_contact.py", "tests/test_impact_qp.py"),
    ),
    Mutant(
        "bridge-no-final-projection",
        "singular-position bridge: the state after the step is not projected onto the constraints",
        "simulation/crossing.py",
        "for _ in range(3):  # Newton steps",
        "for _ in range(0):  # Newton steps",
        ("tests/test_singular_crossing.py",),
    ),
    Mutant(
        "bridge-no-initial-projection",
        "singular-position bridge: the state before the step is not projected onto the constraints",
        "simulation/crossing.py",
        "y_a[:nq], y_a[nq : nq + nv] = project(t_a, y_a[:nq], y_a[nq : nq + nv], y_a[nq + nv : nq + nv + nl])",
        "pass",
        ("tests/test_singular_crossing.py",),
    ),
    Mutant(
        "baumgarte-sign",
        "Baumgarte: J q̈ = φ + αΦ − βg (the velocity term's sign flipped: drift grows)",
        "model/assembly.py",
        "- stab[0] * Phi - stab[1] * g",
        "+ stab[0] * Phi - stab[1] * g",
        ("tests/test_simulate.py", "tests/test_stability.py"),
    ),
    Mutant(
        "projection-velocity-sign",
        "projection: v ← v + A⁻¹D (J A⁻¹D)⁻¹ Φ (moved away from the constraint)",
        "simulation/drift.py",
        "v_new = v - AinvD @ ca.solve(J @ AinvD, Phi)",
        "v_new = v + AinvD @ ca.solve(J @ AinvD, Phi)",
        ("tests/test_simulate.py", "tests/test_stability.py"),
    ),
)


class SnippetError(RuntimeError):
    """A mutant's snippet is not exactly once in its file (the code moved: update the mutant)."""


def mutated_text(mutant: Mutant, root: Path) -> str:
    """The mutant's file under ``root`` with its snippet replaced; :class:`SnippetError` unless it occurs once."""
    path = root / "gausspp" / mutant.file
    text = path.read_text(encoding="utf-8")
    count = text.count(mutant.old)
    if count != 1:
        raise SnippetError(f"mutant {mutant.id!r}: snippet found {count} times in gausspp/{mutant.file}, expected once")
    return text.replace(mutant.old, mutant.new)


def check_mutants(mutants: Iterable[Mutant], root: Path = ROOT) -> None:
    """Every snippet once in its file and every test file present, before anything runs (fail loudly)."""
    for mutant in mutants:
        mutated_text(mutant, root)
        for test in mutant.tests:
            if not (root / test.split("::")[0]).is_file():
                raise SnippetError(f"mutant {mutant.id!r}: no test file {test}")


def sandbox(prefix: str, source: Path = ROOT) -> Path:
    """A fresh temporary copy of the package, tests and pytest configuration under ``source``."""
    folder = Path(tempfile.mkdtemp(prefix=f"gausspp-mutant-{prefix}-"))
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache")
    for name in COPIED:
        path = source / name
        if path.is_dir():
            shutil.copytree(path, folder / name, ignore=ignore)
        elif path.is_file():
            shutil.copy2(path, folder / name)
    return folder


@dataclass(frozen=True)
class Settings:
    """What every run shares: the snapshot of the repository it copies, the limits, where logs go."""

    source: Path  # one copy of the working tree taken at the start: the baseline and every mutant test the same code
    timeout: float = TIMEOUT
    keep: bool = False
    logs: Path | None = None  # each pytest output as <id>.log (none kept without it)
    baseline_failures: frozenset[str] = frozenset()

    def log(self, name: str, output: str) -> None:
        if self.logs is not None:
            self.logs.mkdir(parents=True, exist_ok=True)
            (self.logs / f"{name}.log").write_text(output, encoding="utf-8")


def environment(folder: Path) -> dict[str, str]:
    """The copy first on the import path; a cache directory and a temp directory of its own."""
    cache, tmp = folder / "_cache", folder / "_tmp"
    cache.mkdir()
    tmp.mkdir()
    env = dict(os.environ)
    env.update(PYTHONPATH=str(folder), GAUSSPP_CACHE_DIR=str(cache), TMPDIR=str(tmp), PYTHONDONTWRITEBYTECODE="1")
    return env


def run_pytest(folder: Path, tests: Sequence[str], stop_first: bool, timeout: float) -> tuple[int | None, str]:
    """pytest's exit code (``None`` on timeout) and its output; a timed-out run is ended with its process group."""
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *(["-x"] if stop_first else []), *tests]
    proc = subprocess.Popen(
        command,
        cwd=folder,
        env=environment(folder),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,  # its own process group: a timeout ends pytest and whatever it started
    )
    try:
        output, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        output, _ = proc.communicate()
        return None, output
    return proc.returncode, output


def failed_tests(output: str) -> list[str]:
    """The node ids pytest's short summary lists as FAILED or ERROR (``-ra`` is in the project's addopts)."""
    return re.findall(r"^(?:FAILED|ERROR) (\S+)", output, flags=re.MULTILINE)


def classify(code: int | None, output: str, seconds: float, baseline_failures: frozenset[str]) -> Outcome:
    """killed / SURVIVED / broken / timeout from pytest's exit code (1: tests failed; 2–5: it could not run them)."""
    if code is None:
        return Outcome("timeout", seconds, "")
    if code == 0:
        return Outcome("SURVIVED", seconds, "")
    failures = failed_tests(output)
    if code == 1 and failures:
        first = failures[0]
        return Outcome("baseline-fails" if first in baseline_failures else "killed", seconds, first)
    lines = [line for line in output.splitlines() if "Error" in line] or output.splitlines()[-1:]
    return Outcome("broken", seconds, f"pytest exit {code}: {lines[0].strip()[:100] if lines else ''}")


def run_mutant(mutant: Mutant, settings: Settings) -> Outcome:
    """Apply ``mutant`` in a fresh copy of the snapshot and run its tests there."""
    folder = sandbox(mutant.id, settings.source)
    try:
        (folder / "gausspp" / mutant.file).write_text(mutated_text(mutant, folder), encoding="utf-8")
        start = time.perf_counter()
        code, output = run_pytest(folder, mutant.tests, stop_first=True, timeout=settings.timeout)
        settings.log(mutant.id, output)
        return classify(code, output, time.perf_counter() - start, settings.baseline_failures)
    finally:
        if not settings.keep:
            shutil.rmtree(folder, ignore_errors=True)


def run_baseline(mutants: Sequence[Mutant], settings: Settings) -> tuple[frozenset[str], float]:
    """The unmutated snapshot over the union of the mutants' tests: the tests that fail without any mutation."""
    tests = sorted({test for mutant in mutants for test in mutant.tests})
    folder = sandbox("baseline", settings.source)
    try:
        start = time.perf_counter()
        code, output = run_pytest(folder, tests, stop_first=False, timeout=settings.timeout)
        seconds = time.perf_counter() - start
        settings.log("baseline", output)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if code is None:
        raise RuntimeError(f"the baseline run timed out after {settings.timeout:.0f} s")
    if code not in (0, 1):
        raise RuntimeError(f"the baseline run could not run its tests (pytest exit {code}):\n{output[-3000:]}")
    return frozenset(failed_tests(output)), seconds


def short_tests(tests: Sequence[str]) -> str:
    return ", ".join(test.removeprefix("tests/").removesuffix(".py") for test in tests)


def print_table(rows: Sequence[tuple[Mutant, Outcome]]) -> None:
    """The results, one mutant a row, and the summary line."""
    header = ("id", "description", "tests run", "result", "seconds", "caught by / detail")
    table = [
        (m.id, m.description, short_tests(m.tests), o.result, f"{o.seconds:.0f}", o.detail.removeprefix("tests/"))
        for m, o in rows
    ]
    widths = [max(len(str(row[i])) for row in [header, *table]) for i in range(len(header))]
    widths[1], widths[2] = min(widths[1], 60), min(widths[2], 50)

    def line(cells: Sequence[str]) -> str:
        return " | ".join(str(c)[:w].ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()

    print(line(header))
    print("-+-".join("-" * w for w in widths))
    for row in table:
        print(line(row))
    killed = sum(o.result == "killed" for _, o in rows)
    print(f"\n{killed} of {len(rows)} mutants killed")
    for result in ("SURVIVED", "broken", "timeout", "baseline-fails"):
        ids = [m.id for m, o in rows if o.result == result]
        if ids:
            print(f"{result}: {', '.join(ids)}")


def select(only: str | None) -> list[Mutant]:
    """The mutants named by ``--only`` (all without it); an unknown id is an error."""
    if not only:
        return list(MUTANTS)
    by_id = {m.id: m for m in MUTANTS}
    wanted = [name.strip() for name in only.split(",") if name.strip()]
    unknown = [name for name in wanted if name not in by_id]
    if unknown:
        raise SystemExit(f"unknown mutant id(s): {', '.join(unknown)}; see --list")
    return [by_id[name] for name in wanted]


def print_list(mutants: Sequence[Mutant]) -> None:
    """Each mutant: its id, what it does, the edit and the tests that should catch it."""
    for m in mutants:
        print(f"{m.id}\n    {m.description}\n    gausspp/{m.file}: {m.old!r}\n    -> {m.new!r}")
        print(f"    tests: {short_tests(m.tests)}")


def parse(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", metavar="ID[,ID]", help="run only these mutants")
    parser.add_argument("--list", action="store_true", help="print the mutants and exit")
    parser.add_argument("--jobs", type=int, default=1, help="mutants run in parallel (default 1)")
    parser.add_argument("--timeout", type=float, default=TIMEOUT, help="seconds per mutant (default 900)")
    parser.add_argument("--no-baseline", action="store_true", help="skip the run of the unmutated code")
    parser.add_argument("--keep", action="store_true", help="keep each mutant's temporary copy (to inspect it)")
    parser.add_argument("--logs", type=Path, metavar="DIR", help="write each pytest output to DIR/<id>.log")
    return parser.parse_args(argv)


def run_all(mutants: Sequence[Mutant], settings: Settings, jobs: int, baseline: bool) -> list[Outcome]:
    """The baseline (unless skipped), then every mutant, ``jobs`` at a time; each printed as it ends."""
    if baseline:
        print(f"baseline: the unmutated code over the {len({t for m in mutants for t in m.tests})} test files ...")
        failures, seconds = run_baseline(mutants, settings)
        print(f"baseline: {len(failures)} failing test(s) in {seconds:.0f} s", *sorted(failures), flush=True)
        settings = replace(settings, baseline_failures=failures)
    print(f"{len(mutants)} mutant(s), {jobs} at a time ...", flush=True)

    def one(mutant: Mutant) -> Outcome:
        outcome = run_mutant(mutant, settings)
        print(f"  {mutant.id}: {outcome.result} ({outcome.seconds:.0f} s) {outcome.detail}", flush=True)
        return outcome

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:  # each job is its own pytest process
        return list(pool.map(one, mutants))


def main(argv: Sequence[str] | None = None) -> int:
    args = parse(argv)
    mutants = select(args.only)
    check_mutants(mutants)
    if args.list:
        print_list(mutants)
        return 0
    snapshot = sandbox("snapshot")
    try:
        check_mutants(mutants, snapshot)  # the code the mutants run on, should the tree have changed meanwhile
        settings = Settings(snapshot, args.timeout, args.keep, args.logs)
        outcomes = run_all(mutants, settings, args.jobs, not args.no_baseline)
    finally:
        shutil.rmtree(snapshot, ignore_errors=True)
    print()
    print_table(list(zip(mutants, outcomes, strict=True)))
    return 0 if all(o.result == "killed" for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
