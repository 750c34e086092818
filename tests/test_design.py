"""casadi-posture design: an analytic optimum, never worse than the start, the re-solve
check, and every bad --free refused with exit 2."""

from __future__ import annotations

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.problem import load_problem, problem_from_data
from casadi_posture.workplace_design import design, independent_rows, spread

X_M = 0.40  # the wrist's fixed horizontal distance from the shoulder [m]
LOAD_KG = 2.0

ARM = {
    "body": {
        "model": "sagittal_arm",
        "dofs": {
            "shoulder_flexion": {"passive": {"model": "none"}},
            "elbow_flexion": {"passive": {"model": "none"}},
        },
        "half_joints": {
            "shoulder_flexors": {"strength_Nm": 40.0},
            "shoulder_extensors": {"strength_Nm": 40.0},
            "elbow_flexors": {"strength_Nm": 2000.0},
            "elbow_extensors": {"strength_Nm": 2000.0},
        },
    },
    "posture_deg": {"shoulder_flexion": 60.0, "elbow_flexion": 40.0},
    "loads": [{"name": "weight", "at": "wrist", "mass_kg": LOAD_KG}],
    "tasks": [
        {
            "name": "wrist",
            "kind": "position",
            "effector": "wrist",
            "priority": 1,
            "target_m": [X_M, 0.0, -0.10],
        }
    ],
}
Z_KEY = "tasks[0].target_m[2]"


def _lengths(problem) -> tuple[float, float]:
    """Upper arm and forearm-to-wrist lengths [m], read off the model's kinematics."""
    body = problem.body
    wrist = ca.Function("w", [body.q], [body.landmark("wrist")])
    total = -float(wrist(np.zeros(2))[2])
    # flexing the elbow 90° swings the wrist forward by the forearm length
    forearm = float(wrist(np.radians([0.0, 90.0]))[0])
    return total - forearm, forearm


def test_analytic_optimum_of_a_shelf_height() -> None:
    """The wrist at a fixed horizontal distance x from the shoulder, its height z free.

    The elbow is so strong that its load stays below T_0 (never limiting), there are no
    passive torques, and the shoulder flexors carry the arm, so the endurance is largest
    where the shoulder torque is least. By virtual work, with the elbow at x_E and the
    wrist at x (forearm and hand centres of mass on the elbow-wrist line at fractions c_f,
    c_h of the forearm length L_f), the shoulder torque is

        τ_s = g·[(m_u c_u + m_f (1 − c_f) + m_h (1 − c_h))·x_E + (m_f c_f + m_h c_h + m_L)·x],

    whose x_E coefficient is positive for this body (≈ 1.67 kg, the hand's centre beyond
    the wrist takes −0.11 kg off it). x_E = x − L_f·sin(θs + θe) ≥ x − L_f, least with the
    forearm horizontal (θs + θe = 90°); the elbow then lies on the circle |E| = L_u at
    x_E = x − L_f, below the shoulder (the branch above needs θe = 90° − θs < 0, outside the
    elbow's [0, 150]° range): z* = −sqrt(L_u² − (x − L_f)²).
    """
    problem = problem_from_data(ARM, "arm.toml")
    upper, forearm = _lengths(problem)
    expected = -math.sqrt(upper**2 - (X_M - forearm) ** 2)
    answer = design(problem, {Z_KEY: (-0.40, 0.05)})
    assert answer.success, answer.status
    assert answer.best_m[0] == pytest.approx(expected, abs=1e-4)
    assert answer.best.group == "shoulder_flexors"
    q = answer.best_answer.torques.q
    assert math.degrees(q[0] + q[1]) == pytest.approx(90.0, abs=0.05)
    # the optimum beats every other height the IK reaches
    for z in (expected - 0.03, expected + 0.03):
        other = design(load_other(z), {Z_KEY: (-0.40, 0.05)}).start
        assert other.value < answer.best.value


def load_other(z: float):
    return problem_from_data(ARM, "arm.toml", {Z_KEY: z})


def test_the_re_solve_check_agrees_when_every_level_binds() -> None:
    """One position task on two DOFs: the posture is a function of the design, so the IK
    re-solved at the best design is the NLP's posture."""
    answer = design(problem_from_data(ARM, "arm.toml"), {Z_KEY: (-0.40, 0.05)})
    assert answer.dropped == ()
    assert answer.agrees
    assert answer.check.value == pytest.approx(answer.best.value, rel=1e-6)
    assert answer.posture_gap_deg < 1e-3
    assert answer.kept_residual < 1e-8


@pytest.mark.parametrize(
    ("name", "free"),
    [
        ("holding_horizontal.toml", {"tasks[0].point_m[2],tasks[1].target_m[2]": (-0.5, 0.1)}),
        ("holding_m45.toml", {"tasks[0].point_m[0],tasks[1].target_m[0]": (0.25, 0.45)}),
        ("standing_shelf_box.toml", {"tasks[2].target_m[2],tasks[3].target_m[2]": (1.0, 1.6)}),
    ],
)
def test_the_design_is_never_below_the_start(name: str, free: dict) -> None:
    answer = design(load_problem(PROBLEMS / name), free)
    assert answer.success, answer.status
    assert answer.best.value >= answer.start.value
    assert answer.kept_residual <= 1e-4
    if answer.agrees:
        assert not answer.flags
    else:  # the NLP's posture is also judged: on the shelf it twists the trunk (flagged)
        assert _re_solve_flag(answer) in answer.flags
    assert answer.gain == pytest.approx(answer.check.value - answer.start.value)


def _re_solve_flag(answer) -> str:
    """The flag of a re-solved IK that settles elsewhere than the NLP (the standing shelf:
    the comfort level pulls the re-solve toward neutral)."""
    assert not answer.agrees
    return next(f for f in answer.flags if f.startswith("the re-solved IK"))


def test_a_re_solve_that_differs_is_flagged_and_exits_1() -> None:
    """The standing shelf: the NLP drops the comfort level, the re-solve keeps it, so the
    two postures differ; the answer is the re-solve's gain, flagged (exit 1)."""
    args = ["design", str(PROBLEMS / "standing_shelf_box.toml"), "--free"]
    args += ["tasks[2].target_m[2],tasks[3].target_m[2]=1.0:1.6", "--json"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 1, result.output
    data = json.loads(result.stdout)
    assert data["check"]["agrees"] is False
    assert any(f.startswith("the re-solved IK") for f in data["flags"])
    start, check = data["start"]["endurance_min"], data["check"]["endurance_min"]
    assert data["gain"]["absolute"] == pytest.approx(check - start)
    assert data["gain"]["nlp_absolute"] == pytest.approx(data["best"]["endurance_min"] - start)


def test_capable_objective_raises_the_share() -> None:
    problem = load_problem(PROBLEMS / "holding_horizontal.toml")
    answer = design(
        problem, {"tasks[0].point_m[2],tasks[1].target_m[2]": (-0.5, 0.1)}, "capable-female"
    )
    assert answer.success
    assert answer.best.value >= answer.start.value
    assert answer.agrees


def test_independent_rows_drops_combinations() -> None:
    rows = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    assert independent_rows(rows) == [0, 3]


SHELF = str(PROBLEMS / "holding_horizontal.toml")
TIED = "tasks[0].point_m[2],tasks[1].target_m[2]"


def test_cli_json_and_figure(tmp_path: Path) -> None:
    out = tmp_path / "design"
    result = CliRunner().invoke(
        main, ["design", SHELF, "--free", f"{TIED}=-0.5:0.1", "--json", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert data["check"]["agrees"] is True
    written = json.loads((out / "design.json").read_text())
    assert len(written["sweep"]) == 15
    held = [s["endurance_min"] for s in written["sweep"] if s["task_kept"]]
    assert 0 < len(held) < 15  # the lowest heights are out of the arm's reach
    assert data["best"]["endurance_min"] >= max(held) * (1 - 1e-9)  # no grid point beats it
    assert (out / "design.png").stat().st_size > 0
    again = CliRunner().invoke(
        main, ["design", SHELF, "--free", f"{TIED}=-0.5:0.1", "--out", str(out)]
    )
    assert again.exit_code == 2 and "--force" in again.stderr


def test_a_load_over_strength_is_flagged_and_has_no_gain_ratio() -> None:
    """20 kg on the hysteresis arm is over strength wherever the line is: endurance 0 at
    the start and at the best, so the gain is 0 and no ratio exists (0/0 is not ∞)."""
    args = ["design", str(PROBLEMS / "line_plane_hysteresis.toml"), "--free"]
    args += ["tasks[0].point_m[2]=-0.5:0.1", "--set", "loads[0].mass_kg=20"]
    result = CliRunner().invoke(main, [*args, "--json"])
    assert result.exit_code == 1, result.output
    data = json.loads(result.stdout)
    assert data["start"]["endurance_min"] == 0 and data["gain"]["ratio"] is None
    assert any("over strength" in flag for flag in data["flags"])
    table = CliRunner().invoke(main, args)
    assert "gain (IK re-solved at the design): +0.000 min\n" in table.output
    assert "×" not in table.output


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--free", "tasks[9].point_m[2]=0:1"], "task index"),
        (["--free", "tasks[0].effector=0:1"], "target coordinate"),
        (["--free", "tasks[1].point_m[2]=0:1"], "target_m[k]"),
        (["--free", "loads[0].mass_kg=1:2"], "landmark"),
        (["--free", "tasks[0].point_m[2]=0.1:-0.5"], "LO < HI"),
        (["--free", "tasks[0].point_m[2]=-0.5:inf"], "finite"),
        (["--free", "tasks[0].point_m[2]=-50:10"], "unit slip"),
        (["--free", "tasks[0].point_m[2]=0:0.1"], "hold the file's value"),
        (["--free", "tasks[0].point_m[2]=-1:0", "--free", "tasks[0].point_m[2]=-1:1"], "once"),
        (["--free", "tasks[0].point_m[2],tasks[1].target_m[0]=-1:1"], "share one value"),
        (["--free", "tasks[0].point_m[2]"], "KEY=LO:HI"),
        (
            ["--free", "tasks[0].point_m[2]=-1:0", "--set", "fatigue.recovery_law=3cc_r"],
            "capable",
        ),
    ],
)
def test_bad_free_exits_2(args: list[str], words: str) -> None:
    result = CliRunner().invoke(main, ["design", SHELF, *args])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert words in lines[0]


def test_more_starts_never_do_worse() -> None:
    problem = load_problem(PROBLEMS / "holding_m45.toml")
    free = {"tasks[0].point_m[0],tasks[1].target_m[0]": (0.25, 0.45)}
    one, three = design(problem, free), design(problem, free, starts=3)
    assert three.success and three.best.value >= one.best.value * (1 - 1e-9)
    assert any("3 starts" in note for note in three.notes)


def test_the_starts_are_a_hammersley_set_that_fills_the_box() -> None:
    """By hand: the radical inverse of 1, 2, 3, 4 in base 2 is .5, .25, .75, .125 and of 1,
    2 in base 3 is 1/3, 2/3; one free quantity gets evenly spaced starts."""
    np.testing.assert_allclose(spread(4, 1).ravel(), [0.25, 0.5, 0.75], rtol=0, atol=1e-15)
    two = spread(5, 2)
    np.testing.assert_allclose(two[:, 0], [0.2, 0.4, 0.6, 0.8], rtol=0, atol=1e-15)
    np.testing.assert_allclose(two[:, 1], [0.5, 0.25, 0.75, 0.125], rtol=0, atol=1e-15)
    np.testing.assert_allclose(spread(3, 3)[:, 2], [1 / 3, 2 / 3], rtol=0, atol=1e-15)
    many = spread(64, 12)
    assert many.shape == (63, 12) and np.all((many > 0) & (many < 1))
    assert not np.allclose(many[:, 0], many[:, 1])  # off the diagonal
    assert spread(1, 2).shape == (0, 2)
