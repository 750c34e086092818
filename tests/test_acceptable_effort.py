"""Potvin's (2012) maximum acceptable effort against duty cycle, and its place beside the
duty-cycle search."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from casadi_posture.ergonomics.acceptable_effort import Guideline
from casadi_posture.problem import load_problem
from casadi_posture.runs.duty_cycle import duty_cycle

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
RULE = Guideline.from_data()


@pytest.mark.parametrize(
    ("duty_cycle_pct", "mae_pct"),
    [
        # by hand: 100·(1 − (DC − 1/28800)^0.24)
        (50.0, 100 * (1 - (0.5 - 1 / 28800) ** 0.24)),  # 15.33 %MVC
        (25.0, 100 * (1 - (0.25 - 1 / 28800) ** 0.24)),  # 28.30 %MVC
        (10.0, 100 * (1 - (0.1 - 1 / 28800) ** 0.24)),  # 42.46 %MVC
    ],
)
def test_the_mae_equation_by_hand(duty_cycle_pct: float, mae_pct: float) -> None:
    assert RULE.mae_pct_mvc(duty_cycle_pct) == pytest.approx(mae_pct, rel=1e-12)


def test_the_equation_s_ends_one_second_per_shift_and_continuous() -> None:
    """One second of effort in an 8-hour shift (28 800 s) is acceptable at 100 %MVC; a
    continuous effort at nearly nothing; the acceptable effort falls as the duty cycle
    rises."""
    assert RULE.mae_pct_mvc(100.0 / 28800) == pytest.approx(100.0)
    assert RULE.mae_pct_mvc(100.0) == pytest.approx(0.0, abs=1e-3)
    values = [RULE.mae_pct_mvc(dc) for dc in (1, 5, 10, 25, 50, 75, 99)]
    assert values == sorted(values, reverse=True)


@pytest.mark.parametrize("effort", [0.5, 5.0, 15.33, 30.0, 60.0, 95.0])
def test_the_duty_cycle_solves_the_equation(effort: float) -> None:
    dc = RULE.duty_cycle_pct(effort)
    assert 0 < dc <= 100
    assert RULE.mae_pct_mvc(dc) == pytest.approx(effort, abs=1e-9)


def test_out_of_range_efforts() -> None:
    assert RULE.duty_cycle_pct(0.0) == 100.0
    assert RULE.duty_cycle_pct(150.0) == pytest.approx(100.0 / 28800)
    with pytest.raises(ValueError):
        RULE.duty_cycle_pct(math.nan)


def test_the_duty_cycle_search_sets_the_guideline_beside_its_answer() -> None:
    """The 2-DOF arm holding 5 kg with 30 s of rest: the guideline is read at the first hold
    step's most loaded group (checked against the run's own loads), and its numbers are the
    equation's at that effort and at our duty cycle."""
    problem = load_problem(PROBLEMS / "holding_horizontal.toml", {"loads[0].mass_kg": 5.0})
    found = duty_cycle(problem, 30.0, horizon_s=600.0)
    assert found.verdict == "bracketed"
    run = next(iter(found.runs.values()))
    first = run.timeline.load[0]
    assert found.effort.load_pct_mvc == pytest.approx(first.max())
    names = [h.name for h in problem.body.half_joints]
    assert found.effort.half_joint == names[int(first.argmax())]
    guide = found.summary()["guideline"]
    assert guide["acceptable_duty_cycle_pct"] == pytest.approx(
        RULE.duty_cycle_pct(found.effort.load_pct_mvc)
    )
    assert guide["acceptable_effort_at_duty_cycle_pct_mvc"] == pytest.approx(
        RULE.mae_pct_mvc(found.duty_cycle_pct)
    )
    assert guide["region_in_guideline_data"] == (found.effort.region in RULE.regions)


def test_no_duty_cycle_has_no_acceptable_effort_at_it_and_a_tie_names_the_right() -> None:
    """20 kg is over the arm's strength: no duty cycle works, so the guideline has no effort
    'at our duty cycle' to give (not the 100 %MVC of a 0 % duty cycle). The shelf's
    symmetric hold loads both shoulders alike: the right, first in the body, is named."""
    heavy = load_problem(PROBLEMS / "holding_horizontal.toml", {"loads[0].mass_kg": 20.0})
    none = duty_cycle(heavy, 30.0, horizon_s=120.0)
    assert none.verdict == "none" and none.effort.load_pct_mvc > 100
    guide = none.guideline()
    assert guide["acceptable_effort_at_duty_cycle_pct_mvc"] is None
    assert guide["acceptable_duty_cycle_pct"] == pytest.approx(100.0 / 28800)
    shelf = load_problem(PROBLEMS / "standing_shelf_box.toml")
    found = duty_cycle(shelf, 30.0, horizon_s=120.0, precision=1.0)
    assert found.effort.half_joint == "shoulder_flexors_r"
