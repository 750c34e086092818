"""The plausibility report (ergonomics/): mirror symmetry of tasks, asymmetry, joints near
a limit, a trunk leaning back while a hand works ahead, time resting on a limit, idle limbs,
against hand-built postures and the shipped problems."""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.ergonomics.mirror import asymmetry, lateral, paired, symmetric
from casadi_posture.problem import load_problem, problem_from_data
from casadi_posture.static import plausibility, solve

SHELF = PROBLEMS / "standing_shelf_box.toml"
WALL = PROBLEMS / "standing_wall_horizontal.toml"


def test_the_shelf_is_symmetric_and_a_shifted_hand_or_load_breaks_it() -> None:
    shelf = load_problem(SHELF)
    assert symmetric(shelf.body, shelf.task_objects(), shelf.loads)
    wall = load_problem(WALL)
    assert not symmetric(wall.body, wall.task_objects(), wall.loads)
    hand = next(i for i, t in enumerate(shelf.spec.tasks) if t.kind == "position")
    target = list(shelf.spec.tasks[hand].target_m)
    moved = problem_from_data(
        shelf.data,
        shelf.path,
        {f"tasks[{hand}].target_m": [target[0], target[1] + 0.01, target[2]]},
    )
    assert not symmetric(moved.body, moved.task_objects(), moved.loads)
    heavier = problem_from_data(
        shelf.data, shelf.path, {"loads[0].mass_kg": shelf.loads[0].mass + 1}
    )
    assert not symmetric(heavier.body, heavier.task_objects(), heavier.loads)


def test_asymmetry_of_a_mirrored_posture_is_zero_and_of_a_skewed_one_by_hand() -> None:
    body = load_problem(SHELF).body
    rng = np.random.default_rng(3)
    q = np.zeros(body.n)
    for i, j in paired(body):
        q[i] = q[j] = rng.uniform(body.lower[i] / 2, body.upper[i] / 2)
    assert asymmetry(body, q)[0] == pytest.approx(0.0, abs=1e-15)
    q[body.index["elbow_flexion_l"]] += math.radians(7.0)
    q[body.index["lumbar_rotation"]] = math.radians(3.0)
    worst, dof = asymmetry(body, q)
    assert math.degrees(worst) == pytest.approx(7.0) and dof == "elbow_flexion_r"
    assert {body.dofs[i].name for i in lateral(body)} == {"lumbar_bending", "lumbar_rotation"}


def test_near_limit_and_the_trunk_leaning_back_while_the_hands_reach() -> None:
    problem = load_problem(SHELF)
    body, checks = problem.body, plausibility(problem)
    knee = body.index["knee_flexion_r"]
    span = body.upper[knee] - body.lower[knee]
    q = np.zeros(body.n)
    q[body.index["shoulder_flexion_r"]] = q[body.index["shoulder_flexion_l"]] = math.radians(90)
    for fraction, listed in ((0.0, True), (0.04, True), (0.06, False)):
        q[knee] = body.lower[knee] + fraction * span
        near = {n.dof: n for n in checks.check(q, "test").near_limits}
        assert ("knee_flexion_r" in near) is listed
        if listed:
            assert near["knee_flexion_r"].distance_pct == pytest.approx(100 * fraction)
            assert near["knee_flexion_r"].side == "lower"
    q[knee] = 0.0
    lumbar = body.index["lumbar_flexion"]
    points = {load.at for load in problem.loads} | {"wrist_r", "wrist_l"}
    front = ca.Function(
        "w", [body.q], [ca.mmax(ca.vertcat(*[body.landmark(p)[0] for p in points]))]
    )
    centre = ca.Function("c", [body.q], [body.point("lumbar_flexion", body.dofs[lumbar].origin)[0]])
    for extension, flagged in ((15.0, True), (5.0, False)):
        q[lumbar] = math.radians(-extension)
        report = checks.check(q, "test")
        leaning = [f for f in report.flags if "leans back" in f]
        assert bool(leaning) is flagged
        ahead = float(front(q)) - float(centre(q))
        assert ahead > 0.2
        if flagged:
            assert f"{ahead:.2f} m ahead" in leaning[0]


def test_time_resting_on_a_limit_from_a_timeline() -> None:
    """The knee rests on its limit from 30 s to the end of a 99 s run: 69 s, flagged on the
    standing body; the planar arm's elbow on its limit is reported, not flagged."""
    problem = load_problem(SHELF)
    body, checks = problem.body, plausibility(problem)
    time = np.arange(100.0)
    q = np.zeros((100, body.n))
    knee = body.index["knee_flexion_l"]
    q[30:, knee] = body.lower[knee]
    held = checks.held_at_limits(time, q)
    knees = [h for h in held if h["dof"] == "knee_flexion_l"]
    assert knees == [
        {
            "dof": "knee_flexion_l",
            "limit_deg": pytest.approx(math.degrees(body.lower[knee])),
            "side": "lower",
            "seconds": 69.0,
        }
    ]
    assert any("knee_flexion_l rests" in f for f in checks.held_flags(held))
    arm = load_problem(PROBLEMS / "holding_m45.toml")
    arm_checks = plausibility(arm)
    elbow = arm.body.index["elbow_flexion"]
    q = np.zeros((100, arm.body.n))
    q[:, elbow] = arm.body.upper[elbow]
    held = arm_checks.held_at_limits(time, q)
    assert held[0]["seconds"] == 99.0 and arm_checks.held_flags(held) == []


def test_idle_limbs_and_the_task_plane() -> None:
    wall = plausibility(load_problem(WALL))
    assert [limb for limb, _ in wall.idle] == ["shoulder_flexion_l and below"]
    assert wall.sagittal and not wall.symmetric
    shelf = plausibility(load_problem(SHELF))
    assert shelf.idle == [] and not shelf.sagittal and shelf.symmetric


def test_torques_reports_and_flags_a_seated_trunk_leaning_back() -> None:
    """Seated, the lumbar spine extended 15° with the arm raised to the table: the hand works
    0.53 m ahead of the lumbar joint, so torques flags it (exit 1) and its JSON carries the
    report; the IK's own posture (9.9° of extension) is not flagged."""
    seated = str(PROBLEMS / "seated_assembly.toml")
    lean = ["--posture", "lumbar_flexion=-15", "--posture", "shoulder_flexion_r=70"]
    result = CliRunner().invoke(main, ["torques", seated, *lean, "--json"])
    assert result.exit_code == 1, result.output
    data = json.loads(result.stdout)
    report = data["plausibility"]
    assert any("leans back (15°" in f for f in report["flags"])
    assert set(report["flags"]) <= set(data["flags"])
    assert report["idle_limbs"][0]["limb"] == "shoulder_flexion_l and below"
    solved = CliRunner().invoke(main, ["solve", seated, "--json"])
    assert solved.exit_code == 0, solved.output
    shelf = CliRunner().invoke(main, ["solve", str(SHELF), "--json"])
    assert json.loads(shelf.stdout)["plausibility"]["asymmetry_deg"] < 1.0


def test_crossed_forearms_are_measured_across_the_trunk_and_flagged() -> None:
    """Standing, elbows bent 90° and both shoulders rotated 70° inwards: each grip lies
    0.108 m past the mid-line (world positions, the trunk upright), 0.215 m crossed. With
    the trunk turned 30° the world's y no longer measures it (0.186 m), the trunk's frame
    does (0.22 m still). 20° of rotation leaves the hands apart: no flag."""
    shelf = load_problem(SHELF)
    body, check = shelf.body, plausibility(shelf)
    grips = ca.Function("grips", [body.q], [ca.horzcat(*map(body.landmark, ("grip_r", "grip_l")))])

    def posture(rotation: float, trunk: float = 0.0) -> np.ndarray:
        q = np.zeros(body.n)
        angles = {"elbow_flexion_r": 90, "elbow_flexion_l": 90, "lumbar_rotation": trunk}
        angles |= {"shoulder_rotation_r": rotation, "shoulder_rotation_l": rotation}
        for name, degrees in angles.items():
            q[body.index[name]] = math.radians(degrees)
        return q

    crossed = posture(70.0)
    right, left = np.asarray(grips(crossed)).T
    assert right[1] - left[1] == pytest.approx(0.215, abs=5e-4)
    flags = [f for f in check.check(crossed, "posture").flags if "forearms cross" in f]
    assert flags == [
        f"posture: the forearms cross (grip_l {right[1] - left[1]:.2f} m to the right of "
        "grip_r across the trunk, > 0.02 m): the hands' targets swapped?"
    ]
    turned = posture(70.0, trunk=30.0)
    right, left = np.asarray(grips(turned)).T
    assert right[1] - left[1] == pytest.approx(0.186, abs=5e-4)
    assert any("(grip_l 0.22 m to the right" in f for f in check.check(turned, "end").flags)
    assert not any("forearms" in f for f in check.check(posture(20.0), "start").flags)


def test_the_shelf_solved_with_its_targets_swapped_is_flagged_and_as_shipped_is_not() -> None:
    swapped = {"tasks[2].target_m": [0.62, 0.15, 1.40], "tasks[3].target_m": [0.62, -0.15, 1.40]}
    crossed = solve(load_problem(SHELF, swapped), "lexicographic")
    assert any("the forearms cross" in f for f in crossed.plausibility.flags)
    assert any("the forearms cross" in f for f in crossed.flags)
    shipped = solve(load_problem(SHELF), "lexicographic")
    assert not any("forearms" in f for f in shipped.flags)
