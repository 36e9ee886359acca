"""Every claim of the README and of docs/ is checked.

* Each ```python block of ``README.md``, ``docs/guide.md`` and ``docs/index.md`` (the site's front page) runs
  on its own, in a fresh interpreter, in a temporary directory, with a non-interactive matplotlib backend. Its expected
  output is written as comment lines ``# → ...`` after the code: the run must print exactly those
  lines up to the numbers, and each claimed number must be the printed one rounded to the digits
  shown (``≤ x`` claims a bound). Blocks with a known closed form are checked against it too.
* Every figure stated in the prose (timings, errors, counts, powers of ten) carries a source comment
  ``<!-- source: ... -->`` later on its line: a benchmark script, a test (``path::name``) or a module
  whose text holds the number, or a ``gausspp ...`` command that prints it. Timings come from
  benchmarks or commands only (tests never time anything). Shell blocks state no figures.
* Every ``gausspp ...`` command named in the docs parses with the real command line; the README
  names every subcommand, and every subcommand's ``--help`` has a description.
* Nothing points at the design notes outside the repository.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import shlex
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

from gausspp.cli.parser import build_parser

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
RUNNABLE = [README, ROOT / "docs" / "guide.md", ROOT / "docs" / "index.md", ROOT / "docs" / "friction.md"]
DOCS = [*RUNNABLE, ROOT / "docs" / "theory.md"]

FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
SOURCE = re.compile(r"<!--\s*source:\s*(.+?)\s*-->")
CLAIM = "# → "
NUMBER = re.compile(r"(≤\s*)?(-?\d+(?:\.\d*)?(?:e[-+]?\d+)?)")
_SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
#: A figure in prose: a power of ten, a number in e-notation, thousands in groups, a number with a unit, a decimal.
FIGURE = re.compile(
    r"10[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+"
    r"|\d+(?:\.\d+)?e[-+]?\d+"
    r"|\d{1,3}(?:[ \u00a0\u202f]\d{3})+(?!\d)"
    r"|\d+(?:\.\d+)?(?:\s?[–-]\s?\d+(?:\.\d+)?)?\s?(?:µs|ms|s|min|%|×)(?!\w)"
    r"|\d+\.\d+"
)
TIMING = re.compile(r"(?:µs|ms|s|min)$")
PLACEHOLDERS = {"SCENE": "pendulum", "STUDY": "realizability"}


# -- reading the docs --------------------------------------------------------------------------------
def _blocks(path: Path, languages: tuple[str, ...]) -> list[str]:
    return [body for lang, body in FENCE.findall(path.read_text()) if lang in languages]


def _prose_lines(path: Path) -> list[tuple[int, str]]:
    """The lines outside fenced code blocks, numbered from 1."""
    lines, inside = [], False
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if line.startswith("```"):
            inside = not inside
        elif not inside:
            lines.append((number, line))
    return lines


@dataclass(frozen=True)
class Number:
    """A number as written: its value, half a unit of its last digit, and whether it is a bound (``≤ x``)."""

    value: float
    tol: float
    bound: bool = False

    @classmethod
    def parse(cls, text: str, bound: bool = False) -> Number:
        mantissa, _, exponent = text.lower().partition("e")
        decimals = len(mantissa.partition(".")[2])
        return cls(float(text), 0.5 * 10.0 ** (int(exponent or 0) - decimals), bound)

    def admits(self, x: float) -> bool:
        return x <= self.value if self.bound else abs(x - self.value) <= self.tol * (1 + 1e-9)


def _numbers(line: str) -> list[Number]:
    return [Number.parse(m.group(2), bound=bool(m.group(1))) for m in NUMBER.finditer(line)]


def _skeleton(line: str) -> str:
    """The line without its numbers and whitespace (the words and brackets must match)."""
    return re.sub(r"\s+", "", NUMBER.sub("#", line))


def _figure_numbers(figure: str) -> list[Number]:
    text = re.sub(r"(?<=\d)[ \u00a0\u202f](?=\d{3})", "", figure.translate(_SUPERSCRIPT))
    if re.fullmatch(r"10-?\d+", text):
        return [Number(10.0 ** int(text[2:]), 0.0)]
    return [Number.parse(m.group(2)) for m in NUMBER.finditer(text.replace("–", " "))]


# -- python blocks: run them, compare the printed output with the claimed one -------------------------
def _block_ids() -> list[tuple[Path, int]]:
    return [(path, i) for path in RUNNABLE for i in range(len(_blocks(path, ("python",))))]


def _run(code: str, cwd: Path) -> list[str]:
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    result = subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]
    return [line for line in result.stdout.splitlines() if line.strip()]


def _claims(code: str) -> list[str]:
    return [line.strip()[len(CLAIM) :] for line in code.splitlines() if line.strip().startswith(CLAIM)]


def _two_masses(claims: list[list[Number]]) -> None:
    """Rod: both at F/(m1+m2), reaction (m1 a, m2 a − F), margin 1. Servo: F/m2, force m1 F/m2 on mass 1, margin √3/2.

    The servo's margin is the cosine, in the metric A⁻¹ = diag(1, 1/3), between the constraint's normal
    J = (−1, 1) and the force direction (1, 0): 1/√(1 + 1/3).
    """
    m1, m2, F = 1.0, 3.0, 2.0
    a_rod, a_servo = F / (m1 + m2), F / m2
    expected = [
        [a_rod, a_rod, m1 * a_rod, m2 * a_rod - F, 1.0],
        [a_servo, a_servo, m1 * a_servo, 0.0, 1.0 / math.sqrt(1.0 + m1 / m2)],
    ]
    for claim, values in zip(claims, expected, strict=True):
        assert all(c.admits(x) for c, x in zip(claim, values, strict=False)), (claim, values)
        assert claim[-1].bound and claim[-1].value <= 1e-12  # QP ≡ direct


def _ball(claims: list[list[Number]]) -> None:
    """Impacts at √(2h/g)·(1, 1 + 2e, 1 + 2e + 2e²) (h = 1, e = 0.5); at rest the floor carries m g."""
    g, e = 9.81, 0.5
    t1 = math.sqrt(2.0 / g)
    times = [t1, t1 * (1 + 2 * e), t1 * (1 + 2 * e + 2 * e**2)]
    assert all(c.admits(t) for c, t in zip(claims[0], times, strict=True))
    assert claims[1][0].admits(g)


def _sweeps(claims: list[list[Number]]) -> None:
    """36 × 17 axes, nothing recomputed on the second call; the pin pulls hardest at the bottom of the swing.

    There, by energy, ω_b² = 2 m g L (sin φ0 + 1)/(Ic + m L²) and the pin load is m g + m L ω_b²
    (m = 1, L = 1, Ic = 0.01).
    """
    assert [c.value for c in claims[0]] == [36 * 17, 36 * 17, 0]
    bottom = [9.81 + 2 * 9.81 * (math.sin(phi0) + 1) / 1.01 for phi0 in (0.0, 0.5, 1.0)]
    assert all(c.admits(x) for c, x in zip(claims[1], bottom, strict=True))


#: Blocks with a closed form, found by a phrase of their code: the claims must agree with it.
def _two_masses_run(claims: list[list[Number]]) -> None:
    """The docs' front page: from rest for 1 s, the rod's masses at F/(m1+m2)·1 s, the motor's at F/m2·1 s."""
    m1, m2, F = 1.0, 3.0, 2.0
    for claim, speed in zip(claims, (F / (m1 + m2), F / m2), strict=True):
        assert len(claim) == 2 and all(c.admits(speed) for c in claim), (claim, speed)


CLOSED_FORMS: dict[str, Callable[[list[list[Number]]], None]] = {
    "traj = gp.simulate(model, [0.0, 1.0], [0.0, 0.0], 1.0)": _two_masses_run,
    "realization=gp.Force(M=lambda q, v, t: [1, 0])": _two_masses,
    'gp.Unilateral(lambda q, t: q[1], name="floor", restitution=0.5)': _ball,
    "gp.sweep(realizability_task": _sweeps,
}


@pytest.mark.parametrize(("path", "index"), _block_ids(), ids=lambda x: x.name if isinstance(x, Path) else str(x))
def test_python_block_prints_what_it_claims(path: Path, index: int, tmp_path: Path) -> None:
    code = _blocks(path, ("python",))[index]
    claims = _claims(code)
    assert claims, f"{path.name} block {index}: state its output as '{CLAIM}...' comment lines"
    printed = _run(code, tmp_path)
    assert len(printed) == len(claims), printed
    for claim, line in zip(claims, printed, strict=True):
        assert _skeleton(claim.replace("≤", "")) == _skeleton(line), (claim, line)
        wanted, got = _numbers(claim), _numbers(line)
        assert len(wanted) == len(got), (claim, line)
        assert all(w.admits(g.value) for w, g in zip(wanted, got, strict=True)), (claim, line)
    for phrase, check in CLOSED_FORMS.items():
        if phrase in code:
            check([_numbers(c) for c in claims])


def test_every_closed_form_check_finds_its_block() -> None:
    code = "\n".join(b for path in RUNNABLE for b in _blocks(path, ("python",)))
    assert all(phrase in code for phrase in CLOSED_FORMS)


# -- figures and their sources ---------------------------------------------------------------------------
def _figures_with_sources(path: Path) -> list[tuple[int, str, str | None]]:
    """(line, figure, source) for every figure in the prose; source None when no comment follows it."""
    found = []
    for number, line in _prose_lines(path):
        pieces = SOURCE.split(line)  # text, source, text, source, ..., text
        for k in range(0, len(pieces), 2):
            source = pieces[k + 1] if k + 1 < len(pieces) else None
            text = re.sub(r"\]\([^)]*\)", "]", pieces[k])  # link targets are no figures
            found += [(number, m.group(0), source) for m in FIGURE.finditer(text)]
    return found


def _check_command(text: str) -> None:
    """Parse a ``gausspp ...`` command line with the real parser (nothing runs)."""
    words = [w for w in shlex.split(text, comments=True) if not w.startswith("[")]
    args = [PLACEHOLDERS.get(w, w) for w in words[1:]]
    try:
        build_parser().parse_args(args)
    except SystemExit as exc:
        raise AssertionError(f"`{text}` is not a valid gausspp command line") from exc


def _literals(path: Path) -> list[float]:
    """Every number written in a file (code or docstring), underscores allowed."""
    return [
        float(m.group(0).replace("_", "")) for m in re.finditer(r"\d[\d_]*(?:\.\d+)?(?:e[-+]?\d+)?", path.read_text())
    ]


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_every_figure_has_an_existing_source(path: Path) -> None:
    for line, figure, source in _figures_with_sources(path):
        where = f"{path.name}:{line}: {figure!r}"
        assert source is not None, f"{where} has no <!-- source: ... --> after it on its line"
        if source.startswith("gausspp "):
            _check_command(source)
            continue
        file, _, test = source.partition("::")
        assert (ROOT / file).is_file(), f"{where}: source {file} does not exist"
        if TIMING.search(figure):
            assert file.startswith("benchmarks/"), f"{where}: a timing comes from a benchmark, not {file}"
        if test:
            assert re.search(rf"^def {re.escape(test)}\(", (ROOT / file).read_text(), re.M), f"{where}: no {source}"
        if file.startswith(("tests/", "gausspp/")):
            literals = _literals(ROOT / file)
            for n in _figure_numbers(figure):
                assert any(n.admits(x) for x in literals), f"{where}: {n.value:g} is not written in {file}"


def test_figure_detection_sees_the_kinds_of_figure_the_docs_use() -> None:
    line = "≈ 2 µs, 52–64 s, 3.6e-6, 65 341 axes, 10⁻⁶, 105× fewer, 9.6 digits; not (12), §2–3 or 1989"
    assert [m.group(0) for m in FIGURE.finditer(line)] == ["2 µs", "52–64 s", "3.6e-6", "65 341", "10⁻⁶", "105×", "9.6"]
    assert [n.value for n in _figure_numbers("65 341")] == [65341.0]
    assert [n.value for n in _figure_numbers("10⁻⁶")] == [1e-6]
    assert Number.parse("3.6e-6").admits(3.59e-6) and not Number.parse("3.6e-6").admits(3.7e-6)


@pytest.mark.parametrize("path", RUNNABLE, ids=lambda p: p.name)
def test_shell_blocks_state_no_figures(path: Path) -> None:
    for block in _blocks(path, ("bash", "sh", "console")):
        assert not FIGURE.search(block), f"{path.name}: a figure in a shell block cannot carry its source:\n{block}"


# -- the command line the docs name ----------------------------------------------------------------------
def _commands(path: Path) -> list[str]:
    text = path.read_text()
    spans = re.findall(r"`(?:\.venv/bin/)?(gausspp [^`]+)`", text)
    shell = [
        m.group(1)
        for block in _blocks(path, ("bash", "sh"))
        for m in re.finditer(r"^(?:\.venv/bin/)?(gausspp .*)$", block, re.M)
    ]
    return spans + shell


def _subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    [action] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_every_named_command_parses(path: Path) -> None:
    for command in _commands(path):
        _check_command(command)


def test_readme_names_every_subcommand() -> None:
    text = README.read_text()
    missing = [name for name in _subcommands() if f"`gausspp {name}" not in text]
    assert not missing, f"the README's command list lacks {missing}"


@pytest.mark.parametrize("name", list(_subcommands()))
def test_every_subcommand_help_has_a_description(name: str) -> None:
    help_text = _subcommands()[name].format_help()
    usage, _, rest = help_text.partition("\n\n")
    assert not rest.startswith(("positional arguments:", "options:")), f"`gausspp {name} --help` has no description"


# -- no pointers outside the repository ------------------------------------------------------------------
@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_docs_point_only_inside_the_repository(path: Path) -> None:
    text = path.read_text()
    assert "shared/" not in text and "DESIGN" not in text
    for target in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", text):
        if not re.match(r"https?://", target):
            assert (path.parent / target).exists(), f"{path.name} links to {target}, which is not in the repository"


def test_readme_links_the_theory() -> None:
    assert "](docs/theory.md)" in README.read_text()
