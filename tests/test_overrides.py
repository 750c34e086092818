"""Dotted-key overrides of problem files."""

from __future__ import annotations

import re

import pytest
from conftest import PROBLEMS

from casadi_posture.errors import ProblemError
from casadi_posture.problem import load_problem
from casadi_posture.spec.overrides import apply, parse_key, parse_value


def test_keys_and_values_parse() -> None:
    assert parse_key("loads[0].mass_kg") == ["loads", 0, "mass_kg"]
    assert parse_key("loads.0.mass_kg") == ["loads", 0, "mass_kg"]
    assert parse_key("body.dofs.elbow_flexion.range_deg") == [
        "body",
        "dofs",
        "elbow_flexion",
        "range_deg",
    ]
    assert [parse_value(v) for v in ("5", "2.5", "passive", "true", "[0, 150]")] == [
        5,
        2.5,
        "passive",
        True,
        [0, 150],
    ]
    with pytest.raises(ProblemError):
        parse_key("loads[x].mass")


def test_overrides_set_nested_keys_without_touching_the_original() -> None:
    raw = {"loads": [{"mass_kg": 2.5}], "fatigue": {"strategy": "active"}}
    out = apply(
        raw, {"loads[0].mass_kg": 5.0, "fatigue.r_min": 0.2, "simulation.duration_s": 60}, None
    )
    assert out == {
        "loads": [{"mass_kg": 5.0}],
        "fatigue": {"strategy": "active", "r_min": 0.2},
        "simulation": {"duration_s": 60},
    }
    assert raw["loads"][0]["mass_kg"] == 2.5


def test_overridden_problems_are_validated_like_files() -> None:
    problem = load_problem(
        PROBLEMS / "holding_m45.toml", {"loads[0].mass_kg": 5.0, "tasks[0].elevation_deg": -25.0}
    )
    assert problem.loads[0].mass == 5.0
    with pytest.raises(ProblemError, match=re.escape("loads[0].mass_kg = -1")):
        load_problem(PROBLEMS / "holding_m45.toml", {"loads[0].mass_kg": -1.0})
    with pytest.raises(ProblemError, match="an index of an existing list item"):
        load_problem(PROBLEMS / "holding_m45.toml", {"loads[3].mass_kg": 1.0})
