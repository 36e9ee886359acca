"""Issue 30, item 5: `gausspp scenes NAME` documents every parameter of every scene — its meaning, unit and
allowed values — from the "Parameters" section of the scene's builder (:mod:`gausspp.scenes.parameter_docs`).

The checker is first shown to catch an undocumented parameter, an entry without a unit and an entry for a
parameter that does not exist; then every scene passes it, the listing shows every entry, and each documented
simple bound (``> 0``, ``≥ 0``) is one the scene enforces.
"""

from __future__ import annotations

import inspect
import re

import pytest

import gausspp as gp
from gausspp import cli
from gausspp.cli.commands import plain
from gausspp.errors import GaussppError, UnknownNameError
from gausspp.scenes import parameter_docs as docs

NAMES = gp.scenes.names()


def _flat(text: str) -> str:
    """``text`` as the terminal shows it, on one line (the listing wraps long texts at spaces)."""
    return " ".join(plain(text).split())


def _listing(name: str, capsys: pytest.CaptureFixture[str]) -> str:
    assert cli.main(["scenes", name]) == 0
    return capsys.readouterr().out


# -- the checker catches what it should ---------------------------------------------------------------
def _fake(m: float = 1.0, L: float = 2.0, t_end: float = 1.0) -> None:
    """A fake builder.

    Parameters
    ----------
    m : float
        Mass of the body (kg). Allowed: > 0.
    L : float
        Length of the rod. Allowed: > 0.
    g : float
        Gravity (m/s²). Allowed: > 0.
    """


def test_the_checker_finds_an_undocumented_parameter_a_missing_unit_and_a_stray_entry() -> None:
    found = docs.problems(_fake)
    assert any("t_end is not documented" in p for p in found), found  # in the signature, not in the docstring
    assert any("L has no unit" in p for p in found), found
    assert any("g is documented but is no parameter" in p for p in found), found
    assert not any(" m " in p for p in found), found  # the complete entry passes
    assert len(found) == 3


def test_an_undocumented_scene_parameter_would_fail_the_tests(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Drop ``k`` from the two-masses docstring: the checker names it and the listing says it is not documented."""
    build = docs.source("two-masses")
    doc = build.__doc__ or ""
    entry = re.search(r"\n    k : float\n(        .*\n)+", doc)
    assert entry is not None
    monkeypatch.setattr(build, "__doc__", doc.replace(entry.group(0), "\n"))
    assert docs.problems(build) == ["build: k is not documented"]
    assert docs.describe("two-masses")["k"].meaning == ""
    out = _listing("two-masses", capsys)
    assert "(not documented)" in out and "(unit not documented)" in out


def test_a_description_splits_into_meaning_unit_and_allowed_values() -> None:
    assert docs.split("Mass of the (first) body (kg). Allowed: > 0.") == ("Mass of the (first) body", "kg", "> 0")
    assert docs.split("Slope of the track (-). Allowed: any\n   finite number.") == (
        "Slope of the track",
        "-",
        "any finite number",
    )
    assert docs.split("Slope of the track. Allowed: any finite number.")[1] == ""  # no unit: empty, reported
    assert docs.split("Slope of the track (-).")[2] == ""  # no allowed values: empty, reported


def test_an_unknown_scene_is_a_project_error() -> None:
    with pytest.raises(UnknownNameError, match="nosuch"):
        docs.describe("nosuch")


# -- every scene -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_every_parameter_of_the_scene_is_documented(name: str) -> None:
    builder = docs.source(name)
    assert docs.problems(builder) == []
    signature = [k for k, p in inspect.signature(builder).parameters.items() if p.kind is not p.VAR_KEYWORD]
    assert set(docs.documented(builder)) == set(signature)  # nothing undocumented, nothing documented in excess
    described = docs.describe(name)
    assert list(described) == list(gp.scenes.parameters(name))  # the parameters `gausspp run NAME` takes
    for key, doc in described.items():
        assert doc.meaning and doc.unit and doc.allowed, (name, key, doc)
        assert doc.default == gp.scenes.parameters(name)[key].default


@pytest.mark.parametrize("name", NAMES)
def test_the_listing_shows_every_parameters_name_unit_meaning_and_allowed_values(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = _listing(name, capsys)
    flat = " ".join(out.split())
    table = out.split("--param KEY=VALUE):\n")[1].splitlines()
    assert "Parameters" not in out and "----------" not in out  # the section is shown as the table, not as text
    for key, doc in docs.describe(name).items():
        header = next((line for line in table if line.startswith(f"  {key} ")), None)
        assert header is not None, (name, key)
        assert header.rstrip().endswith(f"({doc.unit})") and f"default {doc.default!r}" in header, header
        assert _flat(doc.meaning) in flat, (name, key)
        assert f"allowed: {_flat(doc.allowed)}" in flat, (name, key)
    assert all(len(line) <= 100 for line in table), name


# -- the documented bounds are the scenes' ------------------------------------------------------------------
def _simple_bounds() -> list[tuple[str, str, float]]:
    """Every parameter documented as ``> 0`` or ``≥ 0`` (and checked), with a value just outside the bound."""
    cases = []
    for name in NAMES:
        for key, doc in docs.describe(name).items():
            bound = re.match(r"([>≥]) 0(?![.\d])", doc.allowed)
            if bound and "not checked" not in doc.allowed:
                cases.append((name, key, 0.0 if bound.group(1) == ">" else -1.0))
    return cases


BOUNDS = _simple_bounds()


def test_many_bounds_are_checked() -> None:
    assert len(BOUNDS) > 60
    assert ("two-masses", "k", -1.0) in BOUNDS and ("block-on-floor", "drop", -1.0) in BOUNDS
    assert ("crane", "M0", 0.0) in BOUNDS and ("overhead-crane", "g", 0.0) in BOUNDS
    assert not any(key == "g" and name == "pendulum" for name, key, _ in BOUNDS)  # documented as not checked


@pytest.mark.parametrize(("name", "key", "bad"), BOUNDS, ids=[f"{n}-{k}" for n, k, _ in BOUNDS])
def test_a_value_outside_a_documented_bound_is_refused(name: str, key: str, bad: float) -> None:
    with pytest.raises(GaussppError) as caught:
        gp.scenes.get(name, **{key: bad})
    assert key in str(caught.value), str(caught.value)
