"""Dotted-key overrides of problem files."""

from __future__ import annotations

import re

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
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


def test_a_title_says_what_the_overrides_changed(tmp_path) -> None:
    """The shelf template's title names a 4 kg box 1.20 m high: with the box set to 6 kg the
    title says so, in describe's header and in solve's report.html; without overrides,
    or with the title itself set, the title stands as written."""
    from click.testing import CliRunner

    from casadi_posture.cli import main

    shelf = tmp_path / "shelf.toml"
    assert CliRunner().invoke(main, ["init", "shelf", str(shelf)]).exit_code == 0
    written = load_problem(shelf).spec.title
    assert "4 kg box" in written and load_problem(shelf).heading == written
    mass = {"loads[0].mass_kg": 6.0, "loads[1].mass_kg": 6.0}
    assert load_problem(shelf, mass).heading == (
        f"{written} (changed: loads[0].mass_kg = 6, loads[1].mass_kg = 6)"
    )
    mine = mass | {"title": "A 6 kg box"}
    assert load_problem(shelf, mine).heading == "A 6 kg box"
    many = {
        "loads[0].mass_kg": 6.0,
        "fatigue.strategy": "passive",
        "fatigue.r_min": 0.8,
        "fatigue.fatigue_threshold": 0.7,
        "fatigue.recovery_threshold": 0.4,
        "solver.name": "nullspace",
    }
    assert load_problem(shelf, many).heading.endswith(
        "(changed: loads[0].mass_kg = 6, fatigue.strategy = passive, fatigue.r_min = 0.8, "
        "fatigue.fatigue_threshold = 0.7, and 2 more)"
    )
    hold = str(PROBLEMS / "holding_m45.toml")
    sets = ["--set", "loads[0].mass_kg=6"]
    described = CliRunner().invoke(main, ["describe", hold, *sets])
    title = load_problem(hold).spec.title
    assert described.output.splitlines()[0] == (f"{hold}: {title} (changed: loads[0].mass_kg = 6)")
    out = tmp_path / "solve"
    solved = CliRunner().invoke(main, ["solve", hold, *sets, "--out", str(out)])
    assert solved.exit_code in (0, 1), solved.output
    page = (out / "report.html").read_text()
    assert f"<h1>{title} (changed: loads[0].mass_kg = 6)</h1>" in page


@pytest.mark.parametrize("depth", [17, 300, 600, 5000])
def test_a_deeply_nested_value_is_one_line_naming_the_option(depth: int) -> None:
    """Arrays nested 17 deep are past the problem file's limit (16); 600 deep, past what the
    TOML reader can read (it was an internal RecursionError)."""
    value = "[" * depth + "]" * depth
    runner = CliRunner()
    for args in (["--set", f"fatigue.strategy={value}"], ["--vary", f"title=a,{value}"]):
        command = "solve" if args[0] == "--set" else "whatif"
        result = runner.invoke(main, [command, str(PROBLEMS / "holding_m45.toml"), *args])
        lines = result.stderr.strip().splitlines()
        assert result.exit_code == 2 and len(lines) == 1, result.output
        assert lines[0].startswith(f"error: {PROBLEMS / 'holding_m45.toml'}: ")
        if depth <= 300:
            assert "nested at most 16 deep" in lines[0]
        else:
            assert f"{args[0]}" in lines[0] and "less deeply nested" in lines[0]
