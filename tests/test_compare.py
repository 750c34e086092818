"""The solve and compare commands; the shipped problems agree across solvers."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.problem import load_problem
from casadi_posture.runs.compare import compare

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
