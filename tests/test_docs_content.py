"""The content of the documentation: theory coverage, links that resolve, the course's lectures, README links.

* docs/theory.md names the paper's equation numbers of every realization, of the realizability conditions and of
  the integral principle, has sections on the margin, contacts and saturation, and each of its ``##`` sections
  links at least one gallery example;
* every ``{doc}`` link of docs/*.md points at a page source in the repository (docs/NAME.md, or examples/NAME.py
  for ``auto_examples/NAME``), and every ``theory.md#anchor`` link at a heading of docs/theory.md — with a
  negative control: the same checker refuses a broken link;
* docs/course.md has the six lectures in order, each with its examples and at least two exercises, and the
  numbers its answers state are the library's;
* README.md links the theory and the course with relative paths and nothing outside the repository.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import gausspp as gp
from gausspp.scenes.block_on_floor import bounce_times
from gausspp.studies.figures import three_realizations_runs

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
THEORY = DOCS / "theory.md"
COURSE = DOCS / "course.md"
README = ROOT / "README.md"

DOC_LINK = re.compile(r"\{doc\}`(?:[^`<]*<)?([^`>]+)>?`")
MD_LINK = re.compile(r"\]\(([\w./-]+\.md)(?:#([\w-]+))?\)")
#: The paper's equation numbers the theory page must use (as docs/theory.md writes them, with an en dash):
#: the realizations (2)–(4), (10), (13), (14)–(15), (17)–(18), (19)–(20), (22); the step (1), (5), (11); the
#: realizability conditions (12), (16); the integral principle (23) with its variations (20) and the ideality (21).
EQUATIONS = ["(1)", "(2)–(4)", "(5)", "(10)", "(11)", "(12)", "(13)", "(14)–(15)", "(16)", "(17)–(18)"]
EQUATIONS += ["(19)–(20)", "(20)", "(21)", "(22)", "(23)"]
#: The lectures of docs/course.md, in order, with the examples each one opens.
LECTURES = [
    ("One constraint, three ways", ["two_masses", "one_constraint_three_realizations"]),
    ("Béghin servo", ["crane_servo", "robot_arm_servo"]),
    ("Realizability", ["realizability_map"]),
    ("Vakonomic versus nonholonomic", ["nonholonomic_vs_vakonomic"]),
    ("integral principle (23)", ["verify_a_trajectory"]),
    ("Contacts", ["bouncing_block"]),
]


# -- the checkers ------------------------------------------------------------------------------------
def sections(text: str, level: int = 2) -> dict[str, str]:
    """The sections of a Markdown text at a heading level: heading → body (up to the next heading of that level)."""
    marker = "#" * level + " "
    parts = re.split(rf"^{marker}(.+)$", text, flags=re.M)
    return {heading.strip(): body for heading, body in zip(parts[1::2], parts[2::2], strict=True)}


def slug(heading: str) -> str:
    """MyST's anchor of a heading (``myst_heading_anchors``): lower case, punctuation dropped, spaces to dashes."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(path: Path) -> set[str]:
    return {slug(h) for h in re.findall(r"^#{1,3} (.+)$", path.read_text(), flags=re.M)}


def doc_target_exists(target: str) -> bool:
    """Whether a ``{doc}`` target (relative to docs/) has a page source in the repository."""
    target = target.strip().lstrip("/")
    if target == "auto_examples/index":
        return (ROOT / "examples" / "README.rst").exists()
    if target.startswith("auto_examples/"):
        return (ROOT / "examples" / (target.removeprefix("auto_examples/") + ".py")).exists()
    if target == "api/index":  # the API reference: docs/conf.py writes it at build time from gausspp.__all__
        return 'DOCS / "api" / "index.rst"' in (DOCS / "conf.py").read_text()
    return any((DOCS / (target + suffix)).exists() for suffix in (".md", ".rst"))


def broken_links(text: str) -> list[str]:
    """The links of a docs/ page that do not resolve: ``{doc}`` targets without a source, ``NAME.md#anchor``
    links to a missing page or heading."""
    broken = [target for target in DOC_LINK.findall(text) if not doc_target_exists(target)]
    for page, anchor in MD_LINK.findall(text):
        path = DOCS / page
        if not path.exists() or (anchor and anchor not in anchors(path)):
            broken.append(f"{page}#{anchor}" if anchor else page)
    return broken


def examples_linked(text: str) -> list[str]:
    return [t.removeprefix("auto_examples/") for t in DOC_LINK.findall(text) if t.startswith("auto_examples/")]


def exercises(body: str) -> list[str]:
    """The numbered items after a lecture's "**Exercises.**" line."""
    _, _, after = body.partition("**Exercises.**")
    return re.findall(r"^\d+\. (.+)$", after, flags=re.M)


# -- theory ------------------------------------------------------------------------------------------
def test_theory_names_the_papers_equation_numbers() -> None:
    text = THEORY.read_text()
    missing = [eq for eq in EQUATIONS if eq not in text]
    assert not missing, f"docs/theory.md does not mention the paper's equations {missing}"


def test_theory_has_sections_on_the_margin_contacts_and_saturation() -> None:
    headings = [h.lower() for h in re.findall(r"^#{2,3} (.+)$", THEORY.read_text(), flags=re.M)]
    for topic in ("realizability margin", "contacts", "saturation", "redundancy", "integral principle (23)"):
        assert any(topic in h for h in headings), f"docs/theory.md has no section on {topic!r}: {headings}"


def test_each_theory_section_links_an_example() -> None:
    unlinked = [heading for heading, body in sections(THEORY.read_text()).items() if not examples_linked(body)]
    assert not unlinked, f"these sections of docs/theory.md link no gallery example: {unlinked}"


# -- links -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("page", sorted(DOCS.glob("*.md")), ids=lambda p: p.name)
def test_links_of_every_docs_page_resolve(page: Path) -> None:
    assert not broken_links(page.read_text()), f"{page.name}: broken links {broken_links(page.read_text())}"


def test_the_link_checker_refuses_broken_links() -> None:
    fake = (
        "Open {doc}`auto_examples/no_such_example` and {doc}`the guide <guide>`, read {doc}`no_such_page`,\n"
        "[the margin](theory.md#the-realizability-margin) and [nothing](theory.md#no-such-heading)."
    )
    assert broken_links(fake) == ["auto_examples/no_such_example", "no_such_page", "theory.md#no-such-heading"]


# -- the course --------------------------------------------------------------------------------------
def test_the_course_has_six_lectures_in_order_with_exercises() -> None:
    lectures = [(h, body) for h, body in sections(COURSE.read_text()).items() if h.startswith("Lecture")]
    assert len(lectures) >= len(LECTURES), f"docs/course.md has {len(lectures)} lectures: {[h for h, _ in lectures]}"
    for number, ((heading, body), (topic, names)) in enumerate(zip(lectures, LECTURES, strict=False), start=1):
        assert heading.startswith(f"Lecture {number}.") and topic.lower() in heading.lower(), (number, heading)
        assert set(names) <= set(examples_linked(body)), f"{heading}: opens {examples_linked(body)}, not {names}"
        assert "theory.md#" in body, f"{heading}: no section of the theory to read"
        assert len(exercises(body)) >= 2, f"{heading}: {len(exercises(body))} exercises"


def _step(name: str, **params: object) -> gp.StepResult:
    scene = gp.scenes.get(name, **params)
    return scene.model.step(0.0, scene.q0, scene.v0)


def _answers() -> list[tuple[str, float, float]]:
    """The numbers the course's answers state: (the text as written, the library's value, the stated value)."""
    two = {"m1": 9.0, "m2": 1.0, "F": 2.0}
    rod, servo = _step("two-masses", **two), _step("two-masses", realization="servo", **two)
    block = gp.scenes.get("block-on-floor", tilt=0.3, e=0.5, drop=0.3, t_end=1.0)
    rest = gp.simulate(block.model, block.q0, block.v0, block.t_end, method="DOP853", rtol=1e-11, atol=1e-13)
    t1 = bounce_times(0.3, 0.5, 9.81, 1)[0]
    skate = gp.scenes.get("skate", v0=2.0, omega0=0.5, t_end=10.0)
    turn = gp.simulate(skate.model, skate.q0, skate.v0, 10.0, method="DOP853", rtol=1e-10, atol=1e-12)
    chains = [gp.scenes.get("spring-chain-servo", n=n) for n in (1, 2, 3, 4)]
    indices = [gp.servo_diagnosis(s.model, 0.0, s.q0, s.v0).index for s in chains]
    return [
        ("`F/(m1 + m2) = 0.2`", rod.a[0], 0.2),
        ("`F/m2 = 2.0`", servo.a[1], 2.0),
        ("≈ 0.316", servo.margin, 0.316),
        ("About `0.063`", _step("crane").margin, 0.063),
        ("about `0.302`", _step("rigid-body-servo", n=(1.0, -1.0, 0.0)).margin, 0.302),
        ("1: a torque along `l`", _step("rigid-body-servo").margin, 1.0),
        ("`2n + 1`: 3, 5, 7, 9", float(np.abs(np.subtract(indices, [3, 5, 7, 9])).max()), 0.0),
        ("`v0/omega0 = 4`", float(np.hypot(turn.q[:, 0], turn.q[:, 1] - 4.0).max()), 4.0),
        ("≈ 0.2473 s", t1, 0.2473),
        ("≈ 0.7419 s", t1 * (1 + 0.5) / (1 - 0.5), 0.7419),
        ("≈ 0.981 J", rest.energy[-1], 0.981),
        ("≈ 4.905 N", float(np.abs(rest.contact_force[-1][:2]).max()), 4.905),
        ("≈ 4.905 N", float(np.abs(rest.contact_force[-1][:2]).min()), 4.905),
    ]


def test_the_course_answers_are_what_the_library_computes() -> None:
    text = COURSE.read_text()
    for written, value, stated in _answers():
        assert written in text, f"docs/course.md no longer states {written!r}"
        digits = max(len(f"{stated:g}".partition(".")[2]), 3)
        assert abs(value - stated) <= 0.5 * 10.0**-digits, f"{written!r}: the library gives {value}"


def test_the_course_ideal_and_servo_coincide_for_a_torque_along_l() -> None:
    runs = three_realizations_runs(n=(1.0, 1.0, 1.0), t_end=1.0)
    assert np.abs(runs["ideal"].v - runs["force"].v).max() < 1e-8
    assert np.abs(runs["ideal"].v - runs["inertial"].v).max() > 1e-3


# -- README ------------------------------------------------------------------------------------------
def test_readme_links_into_the_docs_inside_the_repository() -> None:
    text = README.read_text()
    for page in ("docs/theory.md", "docs/course.md", "docs/guide.md"):
        assert f"]({page})" in text, f"README.md does not link {page}"
    targets = re.findall(r"\]\(([^)\s]+)", text)
    outside = [t for t in targets if "shared" in t or t.startswith(("/", "../", "file:"))]
    assert not outside, f"README.md links outside the repository: {outside}"
    assert "/work/" not in text
    missing = [t for t in targets if "://" not in t and not (ROOT / t.partition("#")[0]).exists()]
    assert not missing, f"README.md links to missing files: {missing}"


@pytest.mark.parametrize("third_row", ["oblique", "distance"])
def test_lecture_7_answers_the_motion_is_the_minimal_one_and_its_multipliers_are_no_longer(third_row: str) -> None:
    redundant = gp.scenes.get("four-bar-redundant", third_row=third_row)
    minimal = gp.scenes.get("four-bar-redundant", redundant=False)
    step = redundant.model.step(0.0, redundant.q0, redundant.v0, solver="qp")
    reference = minimal.model.step(0.0, minimal.q0, minimal.v0, solver="direct")
    scale = np.linalg.norm(reference.a)
    assert np.linalg.norm(step.a - reference.a) <= 1e-9 * scale  # exercise 1: the same acceleration
    assert np.linalg.norm(step.u) <= np.linalg.norm(reference.u) * (1 + 1e-9)  # exercise 2: never longer
    assert step.margin < 1e-8  # exercise 3: the rows are dependent
    with pytest.raises(gp.RealizabilityError, match="not together"):
        redundant.model.step(0.0, redundant.q0, redundant.v0, solver="direct")
