"""RULA and REBA reach the users: the console and JSON of torques, a run's timeline columns,
summary.json and figure, the what-if rows, and the problem file's [ergonomics] table."""

from __future__ import annotations

import csv
import json
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.ergonomics.posture_scores import Assumptions, score_posture
from casadi_posture.output.rows import simulation_row
from casadi_posture.output.scores import lines, static_report
from casadi_posture.problem import problem_from_data

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ROOT / "problems"


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def test_torques_console_shows_the_hand_scored_worksheets() -> None:
    """holding_m45 at its posture (shoulder 16.9°, elbow 77.3°, 2.5 kg held statically),
    scored by hand. RULA: upper arm 1 (−20–20°), lower arm 1 (60–100°), wrist 1, twist 1 →
    Table A 1; muscle use 1, force 2 (2–10 kg static) → C 4; neck 1, trunk 1, legs 1 →
    Table B 1, D 4; Table C(4, 4) = 4: action level 2. REBA: trunk, neck, legs 1 → A 1,
    load 0 (< 5 kg); upper arm 1, lower arm 1, wrist 1 → B 1, coupling good 0; Table C 1,
    activity +1 (static) → 2, low risk."""
    result = run("torques", str(PROBLEMS / "holding_m45.toml"))
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    at = lines.index("RULA and REBA of the posture (docs/rula_reba.md):")
    assert lines[at + 1].startswith(
        "  arm: RULA 4 (action level 2: further investigation is needed and changes may be "
        "required); REBA 2, low risk (action level 1: action may be necessary)"
    )
    assert lines[at + 2].startswith("  assumed: neck, shoulder raised, arm supported, coupling")
    assert "trunk upright" in lines[at + 2]


def test_torques_json_equals_score_posture_on_the_same_posture() -> None:
    path = PROBLEMS / "standing_shelf_box.toml"
    result = run("torques", str(path), "--json")
    data = json.loads(result.output)["rula_reba"]
    problem = cp.load(path)
    expected = score_posture(problem.body, problem.posture, problem.loads, Assumptions())
    assert [s["side"] for s in data["sides"]] == ["r", "l"]
    assert data["sides"] == json.loads(json.dumps([s.to_dict() for s in expected]))
    assert data["from_problem_file"] == {} and data["note"] is None
    assert data["assumed"] == list(expected[0].assumed)
    console = run("torques", str(path)).output
    for side, name in zip(expected, ("right", "left"), strict=True):
        r, b = side.rula, side.reba
        assert f"  {name}: RULA {r.grand} (action level {r.action_level}: {r.action}); " in console
        assert f"REBA {b.reba}, {b.risk} risk (action level {b.action_level}:" in console


def test_solve_carries_the_scores_of_its_solution() -> None:
    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml")
    answer = cp.solve(problem)
    expected = score_posture(problem.body, answer.torques.q, problem.loads)
    assert [s.to_dict() for s in answer.scores] == [s.to_dict() for s in expected]
    data = json.loads(
        run("solve", str(PROBLEMS / "standing_wall_horizontal.toml"), "--json").output
    )
    assert [s["rula"]["grand"] for s in data["rula_reba"]["sides"]] == [
        s.rula.grand for s in expected
    ]


@pytest.fixture(scope="module")
def wall_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[cp.Simulation, Path]:
    """The standing wall hold for 60 s, written with its figures."""
    out = tmp_path_factory.mktemp("wall")
    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml", {"simulation.duration_s": 60.0})
    run_ = cp.simulate(problem)
    run_.write(out)
    return run_, out


def test_timeline_columns_equal_score_posture_at_sampled_steps(
    wall_run: tuple[cp.Simulation, Path],
) -> None:
    run_, out = wall_run
    result = run_.result
    with (out / "timeline.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == result.timeline.time.size == 61
    problem = result.problem
    for step in (0, 1, 17, 42, 60):
        sides = score_posture(problem.body, result.timeline.q[step], problem.loads)
        for side in sides:
            assert int(rows[step][f"rula_{side.side}"]) == side.rula.grand
            assert int(rows[step][f"reba_{side.side}"]) == side.reba.reba


def test_summary_has_start_end_worst_and_inputs(wall_run: tuple[cp.Simulation, Path]) -> None:
    run_, out = wall_run
    result = run_.result
    report = json.loads((out / "summary.json").read_text())["rula_reba"]
    problem, tl = result.problem, result.timeline
    start, end = report["postures"][0], report["postures"][-1]
    assert (start["posture"], start["time_s"]) == ("start", 0.0)
    assert (end["posture"], end["time_s"]) == ("end", 60.0)
    for entry, step in ((start, 0), (end, -1)):
        for side in score_posture(problem.body, tl.q[step], problem.loads):
            got = entry["sides"][side.side]
            assert (got["rula"], got["rula_action_level"]) == (
                side.rula.grand,
                side.rula.action_level,
            )
            assert (got["reba"], got["reba_risk"]) == (side.reba.reba, side.reba.risk)
    with (out / "timeline.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    highest = max(int(r[c]) for r in rows for c in ("rula_r", "rula_l"))
    first = next(
        float(r["time_s"]) for r in rows if highest in (int(r["rula_r"]), int(r["rula_l"]))
    )
    assert (report["worst"]["rula"]["score"], report["worst"]["rula"]["time_s"]) == (
        highest,
        first,
    )
    assert report["assumed"][:2] == ["neck", "shoulder raised"] and report["note"] is None
    assert (out / "scores.png").stat().st_size > 10_000


def test_a_run_row_and_a_static_row_carry_the_worst_scores(
    wall_run: tuple[cp.Simulation, Path],
) -> None:
    run_, out = wall_run
    report = json.loads((out / "summary.json").read_text())["rula_reba"]
    row = simulation_row(run_.result)
    assert row["worst_rula"] == report["worst"]["rula"]["score"]
    assert row["worst_rula_action_level"] == report["worst"]["rula"]["action_level"]
    assert row["worst_reba"] == report["worst"]["reba"]["score"]
    assert row["worst_reba_risk"] == report["worst"]["reba"]["risk"]


def test_whatif_rows_follow_the_worksheet_and_the_table_shows_them(tmp_path: Path) -> None:
    """holding_m45 with 1 kg: RULA force 0 (< 2 kg) → C 2, D 2 → grand 2, action level 1;
    with 2.5 kg: force 2 → grand 4, action level 2. REBA's load stays 0 below 5 kg: 2."""
    report = cp.whatif(
        PROBLEMS / "holding_m45.toml", {"loads[0].mass_kg": [1.0, 2.5]}, tmp_path, static=True
    )
    rows = sorted(report.rows, key=lambda r: r["loads[0].mass_kg"])
    assert [(r["worst_rula"], r["worst_rula_action_level"]) for r in rows] == [(2, 1), (4, 2)]
    assert [(r["worst_reba"], r["worst_reba_risk"]) for r in rows] == [(2, "low"), (2, "low")]
    shown = run(
        "whatif", str(PROBLEMS / "holding_m45.toml"), "--vary", "loads[0].mass_kg=1,2.5",
        "--static", "--quiet", "--out", str(tmp_path / "cli"),
    ).output  # fmt: skip
    assert "worst RULA (level)" in shown and "worst REBA (risk)" in shown
    assert "2 (1)" in shown and "4 (2)" in shown and "2 (low)" in shown


def test_arm_supported_lowers_the_upper_arm_score_by_one() -> None:
    """Both worksheets subtract 1 from the upper-arm score when the arm is supported (RULA
    step 1, REBA step 7); the shelf's arms score above 1, so the 1 shows."""
    path = str(PROBLEMS / "standing_shelf_box.toml")
    plain = json.loads(run("torques", path, "--json").output)["rula_reba"]
    held = run("torques", path, "--json", "--set", "ergonomics.arm_supported=true")
    supported = json.loads(held.output)["rula_reba"]
    for a, b in zip(plain["sides"], supported["sides"], strict=True):
        assert a["rula"]["upper_arm"] >= 2 and a["reba"]["upper_arm"] >= 2
        assert b["rula"]["upper_arm"] == a["rula"]["upper_arm"] - 1
        assert b["reba"]["upper_arm"] == a["reba"]["upper_arm"] - 1
        assert "arm supported" in a["assumed"] and "arm supported" not in b["assumed"]
    assert supported["from_problem_file"] == {"arm_supported": True}
    assert "arm supported" not in supported["assumed"]
    console = run("torques", path, "--set", "ergonomics.arm_supported=true").output
    assert "  from the problem's [ergonomics]: arm_supported = true" in console


def test_poor_coupling_adds_two_to_rebas_score_b(tmp_path: Path) -> None:
    """REBA's coupling: good 0, fair 1, poor 2, unacceptable 3 added to score B."""
    text = (
        PROBLEMS / "standing_shelf_box.toml"
    ).read_text() + '\n[ergonomics]\ncoupling = "poor"\n'
    (tmp_path / "poor.toml").write_text(text)
    poor = json.loads(run("torques", str(tmp_path / "poor.toml"), "--json").output)["rula_reba"]
    good = json.loads(run("torques", str(PROBLEMS / "standing_shelf_box.toml"), "--json").output)
    for a, b in zip(good["rula_reba"]["sides"], poor["sides"], strict=True):
        assert (b["reba"]["coupling"], b["reba"]["score_b"]) == (2, a["reba"]["score_b"] + 2)
    assert poor["from_problem_file"] == {"coupling": "poor"}


@pytest.mark.parametrize(
    ("line", "needle"),
    [
        ('coupling = "firm"', "ergonomics.coupling = 'firm': expected 'good', 'fair', 'poor'"),
        ("arm_supported = 3", "ergonomics.arm_supported = 3: expected"),
        ("neck_deg = 120", "ergonomics.neck_deg = 120: expected"),
        ("grip = 1", "ergonomics.grip = 1: expected a known key"),
    ],
)
def test_a_bad_ergonomics_value_exits_2_with_one_line(
    tmp_path: Path, line: str, needle: str
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text((PROBLEMS / "holding_m45.toml").read_text() + f"\n[ergonomics]\n{line}\n")
    result = run("torques", str(path))
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and needle in lines[0], result.stderr


def test_a_body_of_ones_own_is_not_scored_and_says_so() -> None:
    text = (ROOT / "docs" / "problem-files.md").read_text()
    block = next(b for b in text.split("```toml\n")[1:] if b.startswith("[body.tree]"))
    problem = problem_from_data(
        tomllib.loads(block.split("```")[0]) | {"posture_deg": {"swing": 30.0}}, "docs"
    )
    answer = cp.torques(problem)
    assert answer.scores == ()
    assert static_report(problem, answer.scores)["note"].startswith("not scored: RULA/REBA")
    assert lines(problem, answer.scores)[0].startswith("RULA/REBA: not scored")
