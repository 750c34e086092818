"""The L5/S1 compression reaches the users: torques/solve console and JSON with the NIOSH
flag and exit code, a run's timeline columns, summary.json section, flag and figure, the
batch and what-if rows, and "not computed" for a body without a lumbar joint."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner

import casadi_posture as cp
from casadi_posture.biomech.low_back import LowBackModel
from casadi_posture.cli import main
from casadi_posture.output import low_back
from casadi_posture.output.rows import simulation_row

ROOT = Path(__file__).resolve().parents[1]
PROBLEMS = ROOT / "problems"
SHELF = PROBLEMS / "standing_shelf_box.toml"
#: The shelf with the trunk flexed 40°: both hands' loads set per case.
FLEXED = ("--posture", "lumbar_flexion=40")


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def both_hands(kg: float) -> list[str]:
    return ["--set", f"loads[0].mass_kg={kg}", "--set", f"loads[1].mass_kg={kg}"]


def test_torques_json_and_console_equal_the_model_at_the_same_posture() -> None:
    result = run("torques", str(SHELF), *FLEXED, "--json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)["low_back"]
    problem = cp.load(SHELF).with_posture({"lumbar_flexion": 40.0})
    expected = LowBackModel(problem.body, problem.loads).evaluate(problem.posture)
    assert data["compression_N"] == pytest.approx(expected.compression, rel=1e-12)
    assert data["shear_N"] == pytest.approx(expected.shear, rel=1e-12)
    assert data["muscle_force_N"] == pytest.approx(expected.muscle_force, rel=1e-12)
    assert data["sagittal_moment_Nm"] == pytest.approx(expected.sagittal_moment, rel=1e-12)
    assert data["muscle"] == "erector spinae" and data["above_limit"] is None
    assert data["limits_N"] == {"design": 3400.0, "upper": 6400.0}
    assert "Chaffin & Andersson" in data["model"] and data["note"] is None
    console = run("torques", str(SHELF), *FLEXED).output
    assert f"compression {round(expected.compression)} N, shear {round(expected.shear)} N" in (
        console
    )
    assert f"erector spinae force {round(expected.muscle_force)} N" in console
    assert "NIOSH limits: 3400 N design limit, 6400 N upper limit: below the design limit" in (
        console
    )


def test_the_added_load_adds_its_moment_over_the_muscle_arm_and_its_weight_along_the_spine() -> (
    None
):
    """Independent of the model's code: 2 × 5 kg more in the hands, with the trunk flexed 40°
    and nothing bent sideways, adds ΔW·(x_hand − x_L5S1)/0.05 m (the erector spinae carries
    the extra sagittal moment) plus ΔW·cos(trunk from vertical) (the weight along the spine),
    with the hands' and the joint's positions and the trunk's axis from the kinematics
    (g: the body's own)."""
    light, heavy = (
        json.loads(run("torques", str(SHELF), *FLEXED, *both_hands(kg), "--json").output)
        for kg in (1.0, 6.0)
    )
    problem = cp.load(SHELF).with_posture({"lumbar_flexion": 40.0})
    body, q = problem.body, problem.posture
    lumbar = body.dofs[body.index["lumbar_flexion"]]
    where = ca.Function(
        "where",
        [body.q],
        [
            body.point(lumbar.name, lumbar.origin),
            body.landmark("grip_r"),
            body.landmark("grip_l"),
            body.rotation("lumbar_rotation")[:, 2],
        ],
    )
    joint, right, left, spine = (np.asarray(v, dtype=float).ravel() for v in where(q))
    added = 5.0 * body.gravity
    moment = added * ((right[0] - joint[0]) + (left[0] - joint[0]))
    expected = moment / 0.05 + 2 * added * spine[2]
    change = heavy["low_back"]["compression_N"] - light["low_back"]["compression_N"]
    assert change == pytest.approx(expected, rel=1e-9)
    assert math.isclose(spine[2], math.cos(math.radians(40.0)), abs_tol=0.2)


def test_above_the_design_limit_is_flagged_and_exits_1_below_it_not() -> None:
    heavy = run("torques", str(SHELF), *FLEXED, *both_hands(6.0))
    assert heavy.exit_code == 1, heavy.output
    flagged = [line for line in heavy.output.splitlines() if line.startswith("FLAGGED")]
    assert len(flagged) == 1, flagged  # the compression alone: the arms and legs are strong enough
    assert "low-back compression" in flagged[0]
    assert "above the NIOSH design limit of 3400 N" in flagged[0]
    assert "ABOVE the design limit (flagged)" in heavy.output
    data = json.loads(run("torques", str(SHELF), *FLEXED, *both_hands(6.0), "--json").output)
    assert (
        data["low_back"]["compression_N"] > 3400.0 and data["low_back"]["above_limit"] == "design"
    )
    assert data["flags"] == [flagged[0].removeprefix("FLAGGED: ")]
    light = run("torques", str(SHELF), *FLEXED, *both_hands(1.0))
    assert light.exit_code == 0, light.output
    assert "FLAGGED" not in light.output
    deep = run("torques", str(SHELF), "--posture", "lumbar_flexion=60", *both_hands(20.0))
    assert deep.exit_code == 1
    assert "above the NIOSH upper limit of 6400 N" in deep.output
    assert "ABOVE the upper limit (flagged)" in deep.output


def test_solve_carries_the_compression_of_its_solution() -> None:
    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml")
    answer = cp.solve(problem)
    expected = LowBackModel(problem.body, problem.loads).evaluate(answer.torques.q)
    assert answer.low_back == expected
    data = json.loads(
        run("solve", str(PROBLEMS / "standing_wall_horizontal.toml"), "--json").output
    )
    assert data["low_back"]["compression_N"] == pytest.approx(expected.compression, rel=1e-9)


@pytest.fixture(scope="module")
def seated_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[cp.Simulation, Path]:
    """The seated assembly with a 4 kg part for 130 s: the trunk leans as the arm tires (at
    the threshold from 102 s), so the compression varies (864-1516 N); written with its
    figures."""
    out = tmp_path_factory.mktemp("seated")
    problem = cp.load(
        PROBLEMS / "seated_assembly.toml",
        {"simulation.duration_s": 130.0, "loads[0].mass_kg": 4.0},
    )
    run_ = cp.simulate(problem)
    run_.write(out)
    return run_, out


def _timeline(out: Path) -> list[dict[str, str]]:
    with (out / "timeline.csv").open() as handle:
        return list(csv.DictReader(handle))


def test_timeline_columns_equal_the_model_at_sampled_steps(
    seated_run: tuple[cp.Simulation, Path],
) -> None:
    run_, out = seated_run
    result = run_.result
    rows = _timeline(out)
    assert len(rows) == result.timeline.time.size == 131
    model = LowBackModel(result.problem.body, result.problem.loads)
    for step in (0, 1, 50, 104, 130):
        expected = model.evaluate(result.timeline.q[step])
        assert float(rows[step]["compression_N"]) == pytest.approx(expected.compression, rel=1e-9)
        assert float(rows[step]["shear_N"]) == pytest.approx(expected.shear, rel=1e-9, abs=1e-9)
    compression = [float(r["compression_N"]) for r in rows]
    assert max(compression) - min(compression) > 300.0


def test_summary_peak_and_time_above_follow_the_columns(
    seated_run: tuple[cp.Simulation, Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The real limits are not reached (no time above, no flag); with the design limit
    moved into the run's range the time above is the steps above it times their 1 s, each
    step's value held until the next (the last step adds nothing), and the run is flagged."""
    run_, out = seated_run
    report = json.loads((out / "summary.json").read_text())
    back = report["low_back"]
    rows = _timeline(out)
    compression = np.array([float(r["compression_N"]) for r in rows])
    time = np.array([float(r["time_s"]) for r in rows])
    shear = np.array([float(r["shear_N"]) for r in rows])
    peak = int(np.argmax(compression))
    assert back["peak_compression_N"] == pytest.approx(compression[peak], rel=1e-9)
    assert back["peak_compression_time_s"] == time[peak]
    assert abs(back["peak_shear_N"]) == pytest.approx(np.abs(shear).max(), rel=1e-9)
    assert (back["time_above_3400N_s"], back["time_above_6400N_s"]) == (0.0, 0.0)
    assert not [f for f in report["flags"] if "low-back" in f]
    assert (out / "low_back.png").stat().st_size > 10_000

    moved = {"design": 1300.0, "upper": 1450.0}  # within the run's 864-1516 N
    monkeypatch.setattr(low_back, "limits", lambda: moved)
    monkeypatch.setattr("casadi_posture.static.compression_limits", lambda: moved)
    steps = low_back.step_low_back(run_.result)
    again = low_back.run_report(run_.result, steps)
    above = compression[:-1] > moved["design"]
    assert again["time_above_3400N_s"] == pytest.approx(float(above.sum()), abs=1e-9)
    top = compression[:-1] > moved["upper"]
    assert again["time_above_6400N_s"] == pytest.approx(float(top.sum()), abs=1e-9)
    assert 0 < again["time_above_6400N_s"] < again["time_above_3400N_s"] < 130.0
    (flag,) = low_back.run_flags(again)
    assert f"above the NIOSH upper limit of {moved['upper']:g} N" in flag
    assert f"at {time[peak]:g} s" in flag


def test_rest_steps_leave_the_columns_empty(tmp_path: Path) -> None:
    problem = cp.load(
        PROBLEMS / "seated_assembly.toml",
        {"simulation.duration_s": 40.0, "schedule.t_on_s": 20.0, "schedule.t_off_s": 10.0},
    )
    run_ = cp.simulate(problem)
    run_.write(tmp_path, figures=False)
    rows = _timeline(tmp_path)
    rest = [r for r in rows if r["phase"] == "rest"]
    assert len(rest) == 10
    assert all(r["compression_N"] == "" and r["shear_N"] == "" for r in rest)
    assert all(float(r["compression_N"]) > 0 for r in rows if r["phase"] == "hold")


def test_a_run_row_and_whatif_rows_carry_the_compression(
    seated_run: tuple[cp.Simulation, Path], tmp_path: Path
) -> None:
    run_, out = seated_run
    back = json.loads((out / "summary.json").read_text())["low_back"]
    row = simulation_row(run_.result)
    assert row["peak_compression_N"] == back["peak_compression_N"]
    assert row["time_above_3400N_s"] == 0.0
    report = cp.whatif(
        SHELF,
        {"loads[0].mass_kg": [1.0, 6.0], "loads[1].mass_kg": [1.0, 6.0]},
        tmp_path,
        static=True,
        paired=True,
        figures=False,
    )
    rows = sorted(report.rows, key=lambda r: r["loads[0].mass_kg"])
    for case in rows:
        kg = case["loads[0].mass_kg"]
        problem = cp.load(SHELF, {"loads[0].mass_kg": kg, "loads[1].mass_kg": kg})
        q = cp.solve(problem).torques.q
        expected = LowBackModel(problem.body, problem.loads).evaluate(q).compression
        assert case["peak_compression_N"] == pytest.approx(expected, rel=1e-6)
        assert case["time_above_3400N_s"] is None
    assert rows[1]["peak_compression_N"] > rows[0]["peak_compression_N"] + 10 * 9.8
    with (tmp_path / "whatif.csv").open() as handle:
        assert "peak_compression_N" in next(csv.reader(handle))


def test_a_planar_arm_says_not_computed_never_zero(tmp_path: Path) -> None:
    path = PROBLEMS / "holding_horizontal.toml"
    console = run("torques", str(path)).output
    assert "low back: not computed (the body has no lumbar joint)" in console
    assert "compression" not in console
    data = json.loads(run("torques", str(path), "--json").output)["low_back"]
    assert data["compression_N"] is None and data["shear_N"] is None
    assert data["note"] == "not computed (the body has no lumbar joint)"
    assert cp.torques(cp.load(path)).low_back is None
    problem = cp.load(path, {"simulation.duration_s": 5.0})
    run_ = cp.simulate(problem)
    run_.write(tmp_path)
    summary = json.loads((tmp_path / "summary.json").read_text())["low_back"]
    assert summary["peak_compression_N"] is None and summary["time_above_3400N_s"] is None
    assert summary["note"] == "not computed (the body has no lumbar joint)"
    assert "compression_N" not in _timeline(tmp_path)[0]
    assert not (tmp_path / "low_back.png").exists()
    assert simulation_row(run_.result)["peak_compression_N"] is None


def test_sensitivity_ranks_the_compression_with_derivatives_equal_to_finite_differences() -> None:
    """The AD derivative, the posture's own change included, against central differences of
    the solved compression (±0.1 % of each input)."""
    from casadi_posture.sensitivity_analysis.analysis import sensitivity

    result = sensitivity(cp.load(SHELF))
    keys = [item.key for item in result.inputs]
    assert result.compression == pytest.approx(cp.solve(cp.load(SHELF)).low_back.compression)
    for key in ("loads[0].mass_kg", "body.stature_m"):
        value = result.inputs[keys.index(key)].value
        step = 1e-3 * value
        ahead, behind = (
            cp.solve(cp.load(SHELF, {key: value + s})).low_back.compression for s in (step, -step)
        )
        expected = (ahead - behind) / (2 * step)
        assert result.d_compression[keys.index(key)] == pytest.approx(expected, rel=1e-4)
    ranked = result.ranked_compression()
    sizes = [abs(r["compression_elasticity"]) for r in ranked if r["compression_elasticity"]]
    assert sizes == sorted(sizes, reverse=True)
    shown = run("sensitivity", str(SHELF), "--top", "3").output
    assert "low-back compression at L5/S1 2353 N" in shown
    planar = sensitivity(cp.load(PROBLEMS / "holding_horizontal.toml")).to_dict()["low_back"]
    assert planar["compression_N"] is None and planar["ranked"] == []
    assert planar["note"] == "not computed (the body has no lumbar joint)"
