"""The solve and compare commands; the shipped problems agree across solvers."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.problem import load_problem
from casadi_posture.runs.compare import LOCAL_MINIMUM, REACHED, UNREACHABLE, compare, rows

WITH_TASKS = [p for p in sorted(PROBLEMS.glob("*.toml")) if load_problem(p).tasks]


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def _variant(tmp_path: Path, old: str, new: str) -> Path:
    """The -45° holding problem with ``old`` replaced by ``new``, written to ``tmp_path``."""
    text = (PROBLEMS / "holding_m45.toml").read_text()
    assert old in text
    path = tmp_path / "variant.toml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize("path", WITH_TASKS, ids=lambda p: p.stem)
def test_shipped_problems_agree(path: Path) -> None:
    comparison = compare(load_problem(path))
    assert comparison.agree, comparison.verdict
    assert comparison.max_joint_difference_deg < 1e-3


def test_compare_writes_csv_and_skips_problems_without_tasks(tmp_path: Path) -> None:
    result = run("compare", *map(str, sorted(PROBLEMS.glob("*.toml"))), "--out", str(tmp_path))
    assert result.exit_code == 0, result.output
    assert "skipped" in result.stdout and "frontal_elbow" in result.stdout
    with (tmp_path / "compare.csv").open() as handle:
        table = list(csv.DictReader(handle))
    assert len(table) == sum(load_problem(p).hierarchy().depth for p in WITH_TASKS)
    assert all(row["verdict"].startswith("agree") for row in table)
    assert {
        "residual_nullspace",
        "residual_lexicographic",
        "max_joint_difference_deg",
        "time_nullspace_ms",
        "status_lexicographic",
        "unit",
    } <= set(table[0])


def test_compare_explains_an_unreachable_target(tmp_path: Path) -> None:
    path = _variant(tmp_path, "target_m = [0.35, 0.0, -0.25]", "target_m = [0.35, 0.0, -0.95]")
    comparison = compare(load_problem(path))
    assert "unreachable" in comparison.verdict
    assert comparison.nullspace.residuals[1] > 0.1


@pytest.mark.parametrize("solver", ["nullspace", "lexicographic"])
def test_solve_prints_posture_residuals_and_torques(solver: str) -> None:
    path = str(PROBLEMS / "holding_m45.toml")
    data = json.loads(run("solve", path, "--solver", solver, "--json").stdout)
    assert data["success"] and data["solver"] == solver
    assert data["posture_deg"]["shoulder_flexion"] == pytest.approx(16.8833, abs=1e-3)
    assert [lv["unit"] for lv in data["levels"]] == ["m", "m"]
    assert max(lv["residual"] for lv in data["levels"]) < 1e-7
    assert data["torques"]["dofs"][0]["active_Nm"] == pytest.approx(13.698, abs=1e-3)
    text = run("solve", path, "--solver", solver).stdout
    assert "residual" in text and "joints at a limit: none" in text and "load (%MVC)" in text


def test_solve_failure_exits_1_with_status(tmp_path: Path) -> None:
    path = _variant(
        tmp_path, 'name = "lexicographic"', 'name = "lexicographic"\nmax_iterations = 1'
    )
    result = run("solve", str(path))
    assert result.exit_code == 1
    assert "Maximum_Iterations_Exceeded" in result.stdout


def test_solver_options_are_validated(tmp_path: Path) -> None:
    path = _variant(tmp_path, 'name = "lexicographic"', 'name = "lexicographic"\ndamping = 0.01')
    result = run("validate", str(path))
    assert result.exit_code == 2 and "damping only with name = 'nullspace'" in result.stderr


ARM = load_problem(PROBLEMS / "holding_m25.toml").body

#: The paper's arm's upper arm and forearm [m]: shoulder to elbow, elbow to wrist.
LINKS = (
    -ARM.landmarks["elbow"].position[2],
    ARM.landmarks["elbow"].position[2] - ARM.landmarks["wrist"].position[2],
)


def _two_link_ik(x: float, z: float) -> tuple[float, float] | None:
    """The sagittal arm's shoulder and elbow flexion [rad] that put its wrist at (x, 0, z)
    [m] within the joint limits, by two-link inverse kinematics (the law of cosines gives
    the elbow from the shoulder-wrist distance, the direction to the wrist the shoulder;
    both angles from the arm hanging down, forward positive); None when no posture can."""
    upper_arm, forearm = LINKS
    cosine = (x * x + z * z - upper_arm**2 - forearm**2) / (2 * upper_arm * forearm)
    if abs(cosine) > 1:
        return None
    elbow = math.acos(cosine)  # the elbow's range is 0-150°: flexion, never its mirror
    shoulder = math.atan2(x, -z) - math.atan2(
        forearm * math.sin(elbow), upper_arm + forearm * math.cos(elbow)
    )
    if not ARM.lower[1] <= elbow <= ARM.upper[1]:
        return None
    for turn in (-1, 0, 1):
        if ARM.lower[0] <= shoulder + turn * 2 * math.pi <= ARM.upper[0]:
            return shoulder + turn * 2 * math.pi, elbow
    return None


#: A point task for the wrist of the paper's arm, from the file's posture (0.35 m forward,
#: 0.25 m below the shoulder).
POINT = """title = "wrist at a point"
[body]
model = "sagittal_arm"
sex = "male"
stature_m = 1.741
mass_kg = 73.0
[posture_deg]
shoulder_flexion = 16.8833
elbow_flexion = 77.2878
[[tasks]]
name = "wrist_at_point"
kind = "position"
effector = "wrist"
priority = 1
target_m = [{x}, 0.0, {z}]
"""

#: Points in the arm's plane [m]: reachable in front, overhead, behind and just below the
#: shoulder; then beyond the arm's 0.55 m (twice), nearer the shoulder than the 150° elbow
#: folds it, and behind the back past the shoulder's -60° (twice).
POINTS = [(0.35, -0.25), (0.1, 0.45), (-0.2, -0.45), (0.0, -0.3), (0.35, -0.95), (0.7, 0.2),
          (0.05, -0.05), (-0.45, 0.1), (-0.3, -0.3)]  # fmt: skip


@pytest.mark.parametrize(("x", "z"), POINTS)
def test_unreachable_only_where_two_link_ik_has_no_solution(tmp_path: Path, x, z) -> None:
    path = tmp_path / "point.toml"
    path.write_text(POINT.format(x=x, z=z))
    comparison = compare(load_problem(path), starts=4)
    verdicts = [comparison, *comparison.starts.comparisons]
    if _two_link_ik(x, z) is not None:
        assert all("unreachable" not in c.verdict for c in verdicts), comparison.verdict
        assert comparison.outcome in {REACHED, LOCAL_MINIMUM}
    else:
        assert comparison.outcome == UNREACHABLE, comparison.verdict
        assert "level 1 unreachable (" in comparison.verdict


def test_the_points_are_of_both_kinds() -> None:
    reachable = [_two_link_ik(x, z) is not None for x, z in POINTS]
    assert reachable == [True] * 4 + [False] * 5
    # the truth's own check: it finds the posture the file gives for its point
    assert np.degrees(_two_link_ik(0.35, -0.25)) == pytest.approx([16.8833, 77.2878], abs=1e-3)


def test_a_point_inside_the_folded_arm_is_missed_by_the_law_of_cosines(tmp_path: Path) -> None:
    path = tmp_path / "point.toml"
    path.write_text(POINT.format(x=0.05, z=-0.05))
    comparison = compare(load_problem(path))
    upper_arm, forearm = LINKS
    folded = math.sqrt(upper_arm**2 + forearm**2 + 2 * upper_arm * forearm * math.cos(ARM.upper[1]))
    assert comparison.outcome == UNREACHABLE
    assert comparison.nullspace.residuals[0] == pytest.approx(folded - math.hypot(0.05, 0.05))
    assert f"the closest {folded - math.hypot(0.05, 0.05):.3g} m" in comparison.verdict


def test_a_joint_limit_local_minimum_of_a_reachable_line_is_not_unreachable() -> None:
    """The issue's case: from (170.8°, 108.7°) both solvers stop with the arm at both upper
    limits, 0.066 m off the -25° line, which the file's own posture reaches."""
    problem = load_problem(PROBLEMS / "holding_m25.toml")
    assert max(problem.hierarchy().residual_norms(problem.posture)) < 1e-6  # reachable
    comparison = compare(problem.with_posture({"shoulder_flexion": 170.8, "elbow_flexion": 108.7}))
    assert comparison.agree and comparison.outcome == LOCAL_MINIMUM
    assert comparison.nullspace.residuals[0] > 0.06
    assert "unreachable" not in comparison.verdict
    assert comparison.verdict == (
        "agree; both at a local minimum (joint limits: shoulder_flexion at its upper limit, "
        "180°, elbow_flexion at its upper limit, 150°): level 1 reached from another start"
    )


@pytest.mark.parametrize("value", ["0", "1001", "-3", "many"])
def test_starts_is_validated_in_one_line(value: str) -> None:
    result = run("compare", str(PROBLEMS / "holding_m25.toml"), "--starts", value)
    assert result.exit_code == 2
    assert len(result.stderr.strip().splitlines()) == 1 and "--starts" in result.stderr


def test_starts_are_counted_in_the_console_and_compare_csv(tmp_path: Path) -> None:
    path = str(PROBLEMS / "holding_m25.toml")
    result = run("compare", path, "--starts", "6", "--seed", "0", "--out", str(tmp_path))
    with (tmp_path / "compare.csv").open() as handle:
        table = list(csv.DictReader(handle))
    row = table[0]
    counts = {k: int(row[f"starts_{k}"]) for k in ("agree", "reached", "local_minimum",
                                                   "unreachable", "differ")}  # fmt: skip
    assert row["starts"] == "6" and row["starts_seed"] == "0"
    assert counts["agree"] + counts["differ"] == 6
    assert counts["reached"] + counts["local_minimum"] + counts["unreachable"] == counts["agree"]
    assert result.exit_code == (1 if counts["differ"] else 0), result.output
    line = (
        f"{path}: 6 random starts (seed 0): {counts['agree']} agree ({counts['reached']} reach "
        f"the task, {counts['local_minimum']} at a local minimum"
    )
    assert line in result.stdout
    comparison = compare(load_problem(path), starts=6, seed=0)
    assert comparison.starts.local_minimum == counts["local_minimum"]
    assert [c.outcome for c in comparison.starts.comparisons].count(LOCAL_MINIMUM) > 0
    assert row["outcome"] == REACHED and "report.html" in result.stdout
    assert "random starts" in (tmp_path / "report.html").read_text()


def test_each_start_is_its_seeds_draw_and_the_solvers_are_built_once(monkeypatch) -> None:
    from casadi_posture.ik import solvers

    built, make = [], solvers.make_solver
    monkeypatch.setattr(solvers, "make_solver", lambda *a: built.append(a[0]) or make(*a))
    problem = load_problem(PROBLEMS / "holding_m45.toml", {"body.stature_m": 1.6543})
    comparison = compare(problem, starts=5, seed=7)
    body = problem.body
    expected = np.random.default_rng(7).uniform(body.lower, body.upper, size=(5, body.n))
    assert np.array_equal([c.start for c in comparison.starts.comparisons], expected)
    assert built == ["nullspace", "lexicographic"]


def test_every_compare_csv_column_is_documented() -> None:
    text = (PROBLEMS.parent / "docs" / "outputs.md").read_text()
    section = text[text.index("## `compare`") :].split("\n## ")[0]
    comparison = compare(load_problem(PROBLEMS / "holding_m45.toml"), starts=1)
    missing = [c for c in rows(comparison)[0] if f"`{c}`" not in section]
    assert not missing
