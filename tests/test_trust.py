"""Every answer right or visibly flagged: one test per reproducer of the trust issue.

Each case here gave a confident wrong answer, a traceback or a hang on the release before
these checks: an unreachable target solved "successfully", loads above 100 %MVC held,
static and simulated endurances that contradict each other, nan accepted in a file.
"""

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
from casadi_posture.ik import nullspace
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.solvers import make_solver
from casadi_posture.ik.tasks import Position
from casadi_posture.problem import load_problem
from casadi_posture.runs.batch import Case, run_case
from casadi_posture.simulation import simulate

HOLD = PROBLEMS / "holding_m45.toml"
HOLD_TEXT = HOLD.read_text()
REACH = """
[[tasks]]
name = "reach"
kind = "position"
effector = "wrist"
priority = 1
target_m = [0.6, 0.0, 0.0]
"""


def run(*args: str):
    return CliRunner().invoke(main, [str(a) for a in args])


def _reach_problem(tmp_path: Path, duration: float = 60.0) -> Path:
    """The -45° hold with its tasks replaced by a point 0.6 m in front of the shoulder: the
    model arm (0.55 m from shoulder to wrist) cannot reach it."""
    tasks_start, fatigue_start = HOLD_TEXT.index("[[tasks]]"), HOLD_TEXT.index("[fatigue]")
    text = HOLD_TEXT[:tasks_start] + REACH + "\n" + HOLD_TEXT[fatigue_start:]
    path = tmp_path / "reach.toml"
    path.write_text(text.replace("duration_s = 1800.0", f"duration_s = {duration}"))
    return path


def _flagged(output: str) -> list[str]:
    return [line for line in output.splitlines() if line.startswith("FLAGGED: ")]


# 1. Unreachable tasks


def test_solve_flags_an_unreachable_target_and_exits_1(tmp_path: Path) -> None:
    path = _reach_problem(tmp_path)
    for solver in ("lexicographic", "nullspace"):
        text = run("solve", path, "--solver", solver)
        assert text.exit_code == 1, text.output
        assert "NO" in text.output
        assert any("level 1 (reach) not achieved" in f for f in _flagged(text.output))
        data = json.loads(run("solve", path, "--solver", solver, "--json").stdout)
        assert data["reached"] is False and data["levels"][0]["achieved"] is False
        # The closest the arm gets: 0.6 m less the shoulder-to-wrist length.
        assert data["levels"][0]["residual"] == pytest.approx(0.6 - 0.5506, abs=2e-3)


def test_a_point_written_in_centimetres_is_refused_naming_the_unit(tmp_path: Path) -> None:
    path = tmp_path / "cm.toml"
    path.write_text(HOLD_TEXT.replace("point_m = [0.35, 0.0, -0.25]", "point_m = [35, 0, -25]"))
    result = run("solve", path)
    assert result.exit_code == 2
    line = result.stderr.strip()
    assert len(line.splitlines()) == 1
    assert str(path) in line and "tasks[0].point_m[0] = 35" in line and "metres" in line


def test_simulate_says_a_task_out_of_reach_was_never_held(tmp_path: Path) -> None:
    path = _reach_problem(tmp_path)
    result = run("simulate", path, "--out", tmp_path / "run")
    assert result.exit_code == 1, result.output
    assert "task held to the end" not in result.output
    assert "task never held" in result.output
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["stop"] == "never_held"
    assert summary["task"]["held_at_start"] is False and summary["task"]["held_s"] == 0.0
    assert summary["task"]["level1_residual_at_start"] > 0.04
    events = (tmp_path / "run" / "events.csv").read_text()
    assert "task_not_held" in events


def test_whatif_static_marks_unreachable_cases(tmp_path: Path) -> None:
    result = run(
        "whatif",
        HOLD,
        "--vary",
        "tasks[1].target_m=[0.35, 0.0, -0.25],[0.6, 0.0, 0.0]",
        "--vary",
        "tasks[1].priority=1",
        "--static",
        "--quiet",
        "--out",
        tmp_path / "w",
    )
    assert result.exit_code == 1, result.output
    rows = {r["tasks[1].target_m"]: r for r in _csv(tmp_path / "w" / "whatif.csv")}
    near, far = rows["[0.35, 0.0, -0.25]"], rows["[0.6, 0.0, 0.0]"]
    assert near["status"] == "ok" and near["reached"] == "True"
    assert far["status"] == "flagged" and far["reached"] == "False"
    assert float(far["residual_level1_m"]) > 0.04 and "not achieved" in far["flags"]
    assert "NO" in result.output


# 2. Loads above 100 %MVC


def test_torques_over_strength_is_endurance_zero_and_exit_1(tmp_path: Path) -> None:
    path = tmp_path / "heavy.toml"
    path.write_text(HOLD_TEXT.replace("mass_kg = 2.5", "mass_kg = 20.0"))
    args = ("torques", path, "--posture", "shoulder_flexion=90", "--posture", "elbow_flexion=0")
    result = run(*args, "--json")
    assert result.exit_code == 1
    data = json.loads(result.stdout)
    flexors = data["half_joints"][0]
    assert flexors["load_pct_mvc"] > 100 and flexors["endurance_min"] == 0.0
    assert flexors["verdict"] == "over strength" and data["feasible"] is False
    text = run(*args)
    assert text.exit_code == 1 and "OVER STRENGTH" in text.output
    assert "over strength: shoulder_flexors needs" in text.output


def test_a_simulation_over_strength_exhausts_at_once_and_fatigue_stays_at_most_1(
    tmp_path: Path,
) -> None:
    path = tmp_path / "heavy.toml"
    path.write_text(HOLD_TEXT.replace("mass_kg = 2.5", "mass_kg = 20.0"))
    result = run("simulate", path, "--duration", "60", "--out", tmp_path / "run")
    assert result.exit_code == 1, result.output
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["stop"] == "exhausted" and summary["simulated_s"] == 0.0
    assert summary["exhausted_group"]["cause"] == "load above strength"
    assert max(g["max_fatigue"] for g in summary["half_joints"]) == 1.0
    assert any("over strength at the start" in f for f in summary["flags"])
    assert "over_strength" in (tmp_path / "run" / "events.csv").read_text()


def test_the_m45_hold_never_shows_fatigue_above_1(tmp_path: Path) -> None:
    """With the Gymnast-fit elbow passive curve (the default before the limit-torque one),
    the shoulder's recovery goal folds the elbow until its flexors need more than their
    strength: that is an over-strength event that ends the hold, not a fatigue of 1.13."""
    gymnast = {"body.dofs.elbow_flexion.passive.model": "gymnast_fit"}
    result = simulate(
        load_problem(HOLD, {"simulation.duration_s": 400.0, **gymnast}), "lexicographic"
    )
    assert result.timeline.fatigue.max() == 1.0
    over = [e for e in result.events if e.kind == "over_strength"]
    assert over and over[0].half_joint == "elbow_flexors"
    assert result.stop == "exhausted" and result.events[-1].kind == "exhausted"
    assert result.timeline.load[:-1].max() <= 100.0


# 3. One rule for static and simulated endurance


def test_a_load_below_t0_is_unlimited_statically_and_in_the_simulation(tmp_path: Path) -> None:
    """0 kg: the shoulder flexors carry 11.9 %MVC, below T_0 = 15 %MVC."""
    static = run_case(
        Case("s", str(HOLD), {"loads[0].mass_kg": 0.0}, "lexicographic", False, HOLD_TEXT)
    ).row
    assert static["initial_load_shoulder_flexors_pct_mvc"] == pytest.approx(11.9, abs=0.1)
    assert math.isinf(static["initial_endurance_shoulder_flexors_min"])
    assert static["limiting_group_at_start"] == ""
    problem = load_problem(HOLD, {"loads[0].mass_kg": 0.0, "simulation.duration_s": 600.0})
    result = simulate(problem, "lexicographic")
    assert result.stop == "completed" and result.timeline.fatigue.max() == 0.0
    data = json.loads(run("torques", HOLD, "--json").stdout)
    assert "unlimited at or below T_0 = 15 %MVC" in data["endurance_rule"]


def test_a_hanging_arm_never_tires() -> None:
    data = json.loads(
        run(
            "torques",
            PROBLEMS / "holding_m45.toml",
            "--json",
            "--posture",
            "shoulder_flexion=0",
            "--posture",
            "elbow_flexion=0",
        ).stdout
    )
    tiny = [g for g in data["half_joints"] if 0 < g["load_pct_mvc"] < 1]
    assert tiny and all(g["endurance_min"] is None for g in tiny)
    assert {g["verdict"] for g in tiny} == {"unlimited"}


@pytest.mark.parametrize("model", ["threshold", "continuous", "3cc_r"])
def test_static_endurance_is_the_simulated_time_to_exhaustion(model: str) -> None:
    """With the fatigue threshold at 1 the constraint never moves the arm: the simulated hold
    is a constant load, and it must end when the static endurance says."""
    overrides = {
        "fatigue.recovery_law": model,
        "fatigue.fatigue_threshold": 1.0,
        "simulation.duration_s": 900.0,
    }
    problem = load_problem(HOLD, overrides)
    static = run_case(Case("s", str(HOLD), overrides, "lexicographic", False, HOLD_TEXT)).row
    result = simulate(problem, "lexicographic")
    assert result.stop == "exhausted"
    exhausted = next(e for e in result.events if e.kind == "exhausted")
    assert exhausted.half_joint == static["limiting_group_at_start"] == "shoulder_flexors"
    assert exhausted.time_s == pytest.approx(
        60 * static["limiting_endurance_at_start_min"], abs=1.0
    )


# 4. Which group gives out first


def test_limiting_group_at_start_and_exhausted_group_are_both_reported(tmp_path: Path) -> None:
    out = tmp_path / "w"
    result = run(
        "whatif",
        HOLD,
        "--vary",
        "simulation.duration_s=400",
        "--solver",
        "nullspace",
        "--quiet",
        "--out",
        out,
    )
    assert result.exit_code == 0, result.output
    row = _csv(out / "whatif.csv")[0]
    assert row["limiting_group_at_start"] == "shoulder_flexors"
    assert row["exhausted_group"] == "elbow_flexors"
    assert row["task_held_is_lower_bound"] == "False"
    summary = json.loads((out / "cases" / row["case"] / "summary.json").read_text())
    assert summary["limiting_group_at_start"]["half_joint"] == "shoulder_flexors"
    assert summary["exhausted_group"]["half_joint"] == "elbow_flexors"
    assert "limiting group at start" in result.output and "exhausted group" in result.output


def test_a_task_held_to_the_end_is_a_lower_bound(tmp_path: Path) -> None:
    out = tmp_path / "w"
    result = run(
        "whatif",
        HOLD,
        "--vary",
        "loads[0].mass_kg=0",
        "--vary",
        "simulation.duration_s=30",
        "--solver",
        "nullspace",
        "--quiet",
        "--out",
        out,
    )
    assert result.exit_code == 0, result.output
    row = _csv(out / "whatif.csv")[0]
    assert row["task_held_is_lower_bound"] == "True" and float(row["task_held_s"]) == 30.0
    assert "≥ 30.00" in result.output


# 5. The nullspace solver under an inequality that conflicts with level 1


def test_the_nullspace_solver_stalls_instead_of_cycling_to_its_cap() -> None:
    """Keep the wrist on the -45° line with the shoulder forced 20° below its solution: no
    posture satisfies both, and the recursion limit-cycles (to its 1000-iteration cap
    before this check). It must stop early, say so, and return the best posture it passed."""
    problem = load_problem(HOLD)
    hierarchy = problem.hierarchy()
    solver = make_solver("nullspace", hierarchy)
    start = solver.solve(problem.posture).q
    lower_shoulder = Inequality(np.array([1.0, 0.0]), float(start[0] - np.radians(20)))
    result = solver.solve(start, lower_shoulder)
    assert result.status == "stalled" and not result.success
    assert result.iterations <= 2 * nullspace.NullspaceOptions().stall_iterations
    best = make_solver("lexicographic", hierarchy).solve(start, lower_shoulder)
    assert best.success and 0.01 < best.residuals[0] <= result.residuals[0] < 0.02


def test_the_nullspace_solver_leaves_a_worse_rest_for_the_lexicographic_answer(
    tmp_path: Path,
) -> None:
    """A target out of reach with the elbow limited to 60°: from (-50°, 59°) the clamping
    loop came to rest at (-60°, 60°), 3 cm farther from the target than its start, and
    reported that as converged (later: stalled). Released from the shoulder's limit, which
    the task pulls away from, it reaches the lexicographic solver's answer: 0.2647 m, the
    elbow alone at its limit."""
    path = tmp_path / "limited.toml"
    path.write_text(
        HOLD_TEXT.replace(
            "[posture_deg]", "[body.dofs.elbow_flexion]\nrange_deg = [0.0, 60.0]\n\n[posture_deg]"
        ).replace("elbow_flexion = 77.2878", "elbow_flexion = 30.0")
    )
    body = load_problem(path).body
    hierarchy = TaskHierarchy(body, [Position("close", 1, "wrist", (0.15, 0.0, -0.15))])
    start = np.radians([-50.0, 59.0])
    result = make_solver("nullspace", hierarchy).solve(start)
    best = make_solver("lexicographic", hierarchy).solve(start)
    assert best.success and best.residuals[0] == pytest.approx(0.2647, abs=1e-3)
    assert result.status == "converged" and result.success
    assert result.residuals[0] == pytest.approx(best.residuals[0], abs=1e-8)
    assert np.degrees(np.abs(result.q - best.q)).max() < 1e-4
    assert result.at_limits == ("elbow_flexion",)


def test_a_simulation_falls_back_to_the_other_solver_and_records_it() -> None:
    result = simulate(load_problem(HOLD, {"simulation.duration_s": 400.0}), "nullspace")
    fallbacks = [e for e in result.events if e.kind == "solver_fallback"]
    assert fallbacks and "stalled" in fallbacks[0].detail
    steps = [round(e.time_s) for e in fallbacks]
    assert {result.timeline.solver[k] for k in steps} == {"lexicographic"}
    assert result.timeline.solver.count("nullspace") > 150
    assert result.ik_failures == 0 and result.ik_fallbacks == len(fallbacks)


def _csv(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


# Crashes and hangs on input the release accepted


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("mass_kg = 2.5", "mass_kg = 2.5\nforce_N = [nan, 0, 0]", "loads[0].force_N[0] = nan"),
        ("mass_kg = 2.5", "mass_kg = 2.5\nmoment_Nm = [0, inf, 0]", "loads[0].moment_Nm[1] = inf"),
        ("mass_kg = 2.5", "mass_kg = 1e308", "loads[0].mass_kg = 1e+308"),
        ("elevation_deg = -45.0", "direction = [nan, 0, 1]", "tasks[0].direction[0] = nan"),
        ("r_min = 0.9", "r_min = 0.9\nepsilon_Nm = inf", "fatigue.epsilon_Nm = inf"),
        ("duration_s = 1800.0", "duration_s = 1e9", "simulation.duration_s = 1000000000.0"),
        ("time_step_s = 1.0", "time_step_s = 1e-9", "simulation.time_step_s = 1e-09"),
        ("time_step_s = 1.0", "time_step_s = 1e-4", "simulation.time_step_s = 0.0001"),
        (
            'name = "lexicographic"',
            'name = "lexicographic"\nmax_iterations = 2147483648',
            "solver.max_iterations = 2147483648",
        ),
        (
            "mass_kg = 73.0",
            "mass_kg = 73.0\n[body.dofs.elbow_flexion]\npassive = { k1_Nm = 1.0, k2_per_rad = 26.0,"
            " q1_deg = nan, k3_Nm = 1.0, k4_per_rad = 8.0, q2_deg = 120.0 }",
            "body.dofs.elbow_flexion.passive.q1_deg = nan",
        ),
        (
            "mass_kg = 73.0",
            "mass_kg = 73.0\n[body.dofs.elbow_flexion]\npassive = { k1_Nm = 1.0, k2_per_rad = 26.0,"
            " q1_deg = 0.0, k3_Nm = 1.0, k4_per_rad = inf, q2_deg = 120.0 }",
            "body.dofs.elbow_flexion.passive.k4_per_rad = inf",
        ),
        (
            "mass_kg = 73.0",
            "mass_kg = 73.0\n[body.half_joints.elbow_flexors]\nstrength_Nm = 1e-300",
            "body.half_joints.elbow_flexors.strength_Nm = 1e-300",
        ),
    ],
)
def test_every_number_is_finite_and_in_range(tmp_path: Path, old: str, new: str, key: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(HOLD_TEXT.replace(old, new, 1))
    for command in (("validate",), ("torques", "--json"), ("solve", "--json"), ("simulate",)):
        result = run(command[0], path, *command[1:])
        assert result.exit_code == 2, (command, result.output)
        line = result.stderr.strip()
        assert len(line.splitlines()) == 1 and str(path) in line and key in line, line


@pytest.mark.parametrize("duration", ["inf", "1e12", "nan"])
def test_a_duration_option_that_cannot_run_is_refused(tmp_path: Path, duration: str) -> None:
    """A time that is no number is refused by the option's grammar, one too long by the
    file key it sets."""
    result = run("simulate", HOLD, "--duration", duration, "--out", tmp_path / "run")
    assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1
    assert ("simulation.duration_s" if duration == "1e12" else "'--duration'") in result.stderr
    assert not (tmp_path / "run").exists()


def test_deep_nesting_is_one_line_not_a_recursion_error(tmp_path: Path) -> None:
    path = tmp_path / "deep.toml"
    path.write_text("x = " + "[" * 400 + "]" * 400 + "\n" + HOLD_TEXT)
    result = run("validate", path)
    assert result.exit_code == 2 and "nested at most 16 deep" in result.stderr


def test_curve_refuses_an_unknown_figure_format(tmp_path: Path) -> None:
    result = run(
        "curve",
        PROBLEMS / "frontal_elbow.toml",
        "--dof",
        "elbow_flexion",
        "--out",
        tmp_path / "fig.xyz",
    )
    assert result.exit_code == 2 and "--out" in result.stderr and ".png" in result.stderr


@pytest.mark.parametrize(
    ("vary", "needle"),
    [
        ("loads[0].mass_kg=1e308", "loads[0].mass_kg = 1e+308"),
        ("nope=1", "nope = 1: expected a known key"),
        ("loads[5].mass_kg=1", "loads[5].mass_kg = 1: expected an index"),
        ("fatigue.strategy=sideways", "fatigue.strategy = 'sideways'"),
        ("solver=foo", "--vary solver = 'foo'"),
        ("loads[0].mass_kg=1,,2", "no empty value"),
    ],
)
def test_a_bad_vary_is_one_line_before_anything_runs(
    tmp_path: Path, vary: str, needle: str
) -> None:
    out = tmp_path / "w"
    result = run("whatif", HOLD, "--vary", vary, "--static", "--out", out)
    assert result.exit_code == 2, result.output
    line = result.stderr.strip()
    assert len(line.splitlines()) == 1 and str(HOLD) in line and needle in line, line
    assert not out.exists()


def test_a_huge_grid_needs_max_cases(tmp_path: Path) -> None:
    values = ",".join(str(v) for v in range(1, 101))
    args = ["--vary", f"loads[0].mass_kg={values}", "--vary", f"body.mass_kg={values}"]
    result = run("whatif", HOLD, *args, "--static", "--out", tmp_path / "w")
    assert result.exit_code == 2 and "--max-cases 10000" in result.stderr
    assert not (tmp_path / "w").exists()
    small = run(
        "whatif",
        HOLD,
        "--vary",
        "loads[0].mass_kg=1,2",
        "--static",
        "--quiet",
        "--max-cases",
        "1",
        "--out",
        tmp_path / "w",
    )
    assert small.exit_code == 2 and "--max-cases 2" in small.stderr


def test_a_failure_reason_is_one_line_and_the_traceback_goes_to_its_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import casadi_posture.runs.batch as batch

    def broken(problem, solver):
        raise RuntimeError("first line\nsecond line\nthird line")

    monkeypatch.setattr(batch, "solve", broken)
    outcome = run_case(Case("c", str(HOLD), {}, None, False, HOLD_TEXT))
    assert outcome.row["status"] == "failed"
    assert outcome.row["error"] == "RuntimeError: first line"
    story = json.loads(outcome.files["failure.json"])
    assert "Traceback" in story["traceback"] and "third line" in story["traceback"]


def test_option_errors_name_the_problem_file() -> None:
    result = run("torques", HOLD, "--posture", "elbow_flexion")
    assert result.exit_code == 2
    assert result.stderr.startswith(f"error: {HOLD}: --posture")
    result = run("curve", HOLD, "--dof", "knee")
    assert result.exit_code == 2 and result.stderr.startswith(f"error: {HOLD}: --dof")


@pytest.mark.parametrize(
    ("key", "value"),
    [("stature_m", 0.5), ("stature_m", 2.5), ("mass_kg", 10.0), ("mass_kg", 300.0)],
)
def test_the_documented_body_ranges_include_their_ends(key: str, value: float) -> None:
    problem = load_problem(HOLD, {f"body.{key}": value})
    assert getattr(problem.spec.body, key) == value


def test_the_nullspace_solver_never_cycles_to_its_cap_on_a_5_dof_chain() -> None:
    """Random reachable targets on a 3-D chain (5 DOF, non-parallel axes) under random
    inequalities: the recursion often chatters or cycles under an active inequality (the
    cap was reached in a third of these cases). Every run must now end converged or
    stalled well before the cap; a converged posture keeps the inequality and is no worse at
    level 1 than its start (both solvers are local: the lexicographic one may find another
    minimum)."""
    import casadi as ca
    from conftest import chain_3d

    from casadi_posture.ik.tasks import JointReference

    body = chain_3d()
    tip = ca.Function("tip", [body.q], [body.landmark("tip")])
    rng = np.random.default_rng(3)
    statuses = []
    for _ in range(40):
        goal = rng.uniform(0.8 * body.lower, 0.8 * body.upper)
        tasks = [
            Position("tip", 1, "tip", tuple(np.asarray(tip(goal)).ravel())),
            JointReference("rest", 2, ("a", "b", "e"), (0.3, 0.2, 0.1)),
        ]
        hierarchy = TaskHierarchy(body, tasks)
        a = rng.normal(size=5)
        a /= np.linalg.norm(a)
        inequality = Inequality(a, float(a @ goal) - rng.uniform(0.05, 0.5))
        start = np.clip(goal + rng.normal(scale=0.1, size=5), body.lower, body.upper)
        result = make_solver("nullspace", hierarchy).solve(start, inequality)
        statuses.append(result.status.split(";")[0].split(":")[0])
        assert result.iterations < 300, result.status
        if result.success:  # a local minimum (the lexicographic one may be elsewhere)
            assert result.residuals[0] <= hierarchy.residual_norms(start)[0] + 1e-9
            assert inequality.violation(result.q) <= 1e-9
    assert set(statuses) == {"converged", "stalled"}
