"""The scenes' categories are computed from the scenes (gausspp/scenes/categories.py), each rule by what it reads:
the lane kind, the ranks of J and J A⁻¹ D at the initial state, the reaction's width, the mechanism's type, and
the one fact a scene states itself (singular positions along its motion)."""

from __future__ import annotations

from dataclasses import replace

import pytest

import gausspp as gp
from gausspp.scenes.categories import category_of

#: What each built-in scene is, and why (the rule that must decide it).
EXPECTED = {
    "pendulum": ("equality", "two ideal pins, a square system"),
    "andrews": ("equality", "six rows of full rank"),
    "block-on-floor": ("general", "unilateral contacts"),
    "saturated-crane": ("general", "a bounded actuator"),
    "four-bar-redundant": ("general", "rows dependent at the start"),
    "two-actuator-servo": ("general", "two actuators for one constraint"),
    "parallelogram": ("general", "collinear positions along its motion"),
    "overhead-crane": ("servo", "J A⁻¹ D singular: the trolley reaches the payload through the rope"),
    "ur5-tool-path": ("robot", "read from URDF"),
}


@pytest.mark.parametrize("name", list(EXPECTED))
def test_each_rule_decides_the_scene_it_is_about(name: str) -> None:
    assert gp.scenes.category(name) == EXPECTED[name][0], EXPECTED[name][1]


def test_the_categories_partition_the_scenes() -> None:
    kinds = ("equality", "general", "servo", "robot", "unavailable")
    listed = [n for kind in kinds for n in gp.scenes.names(kind)]
    assert sorted(listed) == sorted(gp.scenes.names())


def test_the_stated_fact_and_the_initial_state_each_change_the_verdict() -> None:
    """Controls: the parallelogram without its stated singular positions is an equality scene at its initial state;
    the pendulum stated to pass singular positions becomes general."""
    parallelogram = gp.scenes.get("parallelogram")
    assert category_of(replace(parallelogram, singular_positions=False)) == "equality"
    assert category_of(replace(gp.scenes.get("pendulum"), singular_positions=True)) == "general"


def test_a_scene_that_cannot_be_built_here_is_unavailable(monkeypatch: pytest.MonkeyPatch) -> None:
    def missing_extra() -> gp.scenes.Scene:
        """A scene whose extra is missing."""
        raise gp.BackendUnavailableError("pip install something")

    monkeypatch.setitem(gp.scenes.SCENES, "needs-extra", missing_extra)
    gp.scenes.category.cache_clear()
    try:
        assert gp.scenes.names("unavailable") == ["needs-extra"]
        assert "needs-extra" not in gp.scenes.names("equality")
    finally:
        gp.scenes.category.cache_clear()


def test_an_unknown_category_is_refused_with_the_choices() -> None:
    with pytest.raises(gp.UnknownNameError, match="'equality'"):
        gp.scenes.names("smooth")
