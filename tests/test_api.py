"""The public API, used as a user would: only ``import casadi_posture``."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import pandas
import pytest
from conftest import PROBLEMS

import casadi_posture as cp

HOLD = PROBLEMS / "holding_m45.toml"


def test_load_solve_simulate_frame_compare_whatif(tmp_path: Path) -> None:
    problem = cp.load(HOLD, {"simulation.duration_s": 240.0})
    answer = cp.solve(problem, "nullspace")
    assert answer.reached and not answer.flags
    assert answer.limiting.name == "shoulder_flexors"
    groups = answer.to_frame()
    assert list(groups.columns) == [
        "name",
        "dof",
        "strength_Nm",
        "torque_Nm",
        "load_pct_mvc",
        "endurance_min",
        "verdict",
    ]
    assert groups.loc[0, "load_pct_mvc"] == pytest.approx(31.86, abs=0.01)
    run = cp.simulate(problem, "nullspace")
    timeline = run.to_frame()
    assert timeline.shape[0] == 241 and "shoulder_flexion_deg" in timeline.columns
    assert timeline["shoulder_flexion_deg"].iloc[0] == pytest.approx(16.8833, abs=1e-3)
    flat = pandas.json_normalize(run.summary())
    assert flat.shape[0] == 1 and flat.loc[0, "task.held_s"] == 240.0
    row = run.row()
    assert pandas.DataFrame([row]).shape[0] == 1
    numbers = [v for v in row.values() if isinstance(v, float)]
    assert numbers and all(math.isfinite(v) for v in numbers)
    assert row["initial_endurance_shoulder_extensors_min"] is None  # carries nothing
    comparison = cp.compare(problem)
    assert comparison.agree and list(comparison.to_frame()["level"]) == [1, 2]
    postures = comparison.postures_frame().set_index("dof")
    assert postures.loc["shoulder_flexion", "nullspace_deg"] == pytest.approx(16.8833, abs=1e-3)
    assert postures["difference_deg"].abs().max() < 1e-3
    report = cp.whatif(HOLD, {"loads[0].mass_kg": [1.0, 5.0]}, tmp_path / "w", static=True)
    table = report.to_frame()
    endurance = table.set_index("loads[0].mass_kg")["limiting_endurance_at_start_min"]
    assert endurance[5.0] < endurance[1.0]


def test_problems_from_text_and_from_dict_are_the_file() -> None:
    text = HOLD.read_text()
    from_file, from_text = cp.load(HOLD), cp.loads(text, "hold")
    from_dict = cp.from_dict(tomllib.loads(text), "hold")
    assert from_file.spec == from_text.spec == from_dict.spec
    with pytest.raises(cp.ProblemError, match=r"^hold: loads\[0\]\.mass_kg = -1"):
        cp.loads(text, "hold", {"loads[0].mass_kg": -1})


def test_torques_at_a_posture_and_describe() -> None:
    problem = cp.load(HOLD)
    answer = cp.torques(problem, {"shoulder_flexion": 90.0, "elbow_flexion": 0.0})
    assert answer.dofs_frame().loc[0, "external_Nm"] == pytest.approx(-24.06, abs=0.01)
    assert cp.describe(problem)["dofs"][0]["name"] == "shoulder_flexion"


def test_the_public_names_load_lazily() -> None:
    assert {"load", "solve", "simulate", "whatif", "batch", "Simulation"} <= set(dir(cp))
    with pytest.raises(AttributeError):
        cp.nope  # noqa: B018


def test_curve_gives_the_zeros_of_fig3_and_draws_it(tmp_path: Path) -> None:
    """The frontal elbow (the paper's Fig. 3): the forearm vertical at 90° needs no torque,
    and near each limit passive tissue carries the forearm."""
    fig3 = cp.curve(cp.load(PROBLEMS / "frontal_elbow.toml"), "elbow_flexion")
    zeros = fig3.zeros_frame()
    assert list(zeros["angle_deg"].round(1)) == [1.8, 90.0, 147.7]
    assert [kind.split(":")[0] for kind in zeros["kind"]] == ["passive", "active", "passive"]
    samples = fig3.to_frame()
    assert list(samples.columns) == ["elbow_flexion_deg", "external_Nm", "passive_Nm", "active_Nm"]
    assert (
        samples["active_Nm"] + samples["passive_Nm"] + samples["external_Nm"]
    ).abs().max() < 1e-9
    path = cp.plot_curve(fig3, tmp_path / "fig3.png")
    assert path.stat().st_size > 10_000
    with pytest.raises(cp.ProblemError, match="--force"):
        cp.plot_curve(fig3, path)
    with pytest.raises(cp.ProblemError, match="dof = 'wrist'"):
        cp.curve(cp.load(PROBLEMS / "frontal_elbow.toml"), "wrist")


def test_bad_arguments_are_problem_errors_naming_what_was_expected(tmp_path: Path) -> None:
    problem = cp.load(HOLD)
    with pytest.raises(cp.ProblemError, match=r"solver = 'newton': expected one of"):
        cp.solve(problem, "newton")
    with pytest.raises(cp.ProblemError, match=r"solver = 'Nullspace'"):
        cp.simulate(problem, "Nullspace")
    with pytest.raises(cp.ProblemError, match=r"posture_deg.elbow_flexion = '1.2'"):
        cp.torques(problem, {"elbow_flexion": "1.2"})
    with pytest.raises(cp.ProblemError, match="a mapping of dotted keys"):
        cp.load(HOLD, [("loads[0].mass_kg", 1.0)])
    vary = {"loads[0].mass_kg": [1.0]}
    for kwargs, match in (
        ({"solver": "foo"}, "solver = 'foo'"),
        ({"jobs": 0}, "jobs = 0: expected at least 1"),
    ):
        with pytest.raises(cp.ProblemError, match=match):
            cp.whatif(HOLD, vary, tmp_path / "w", static=True, **kwargs)
    with pytest.raises(cp.ProblemError, match="at least one key to vary"):
        cp.whatif(HOLD, {}, tmp_path / "w", static=True)
    with pytest.raises(cp.ProblemError, match="at least one value"):
        cp.whatif(HOLD, {"loads[0].mass_kg": []}, tmp_path / "w", static=True)
    with pytest.raises(cp.ProblemError, match="solver = 'foo'"):
        cp.batch(PROBLEMS, tmp_path / "b", solver="foo")


def test_whatif_takes_a_loaded_problem_and_batch_a_single_folder(tmp_path: Path) -> None:
    problem = cp.load(HOLD, {"loads[0].mass_kg": 4.0})
    report = cp.whatif(problem, {"body.sex": ["male", "female"]}, tmp_path / "w", static=True)
    loads = report.to_frame().set_index("body.sex")["initial_load_shoulder_flexors_pct_mvc"]
    alone = cp.solve(problem).to_frame().set_index("name").loc["shoulder_flexors"]
    assert loads["male"] == pytest.approx(alone["load_pct_mvc"], rel=1e-9)
    copy = tmp_path / "hold.toml"
    copy.write_text(HOLD.read_text())
    edited = cp.load(copy)
    copy.write_text(HOLD.read_text().replace("mass_kg = 2.5", "mass_kg = 3.0"))
    with pytest.raises(cp.ProblemError, match="has not changed since"):
        cp.whatif(edited, {"body.sex": ["male"]}, tmp_path / "e", static=True)
    folder = tmp_path / "one"
    folder.mkdir()
    (folder / "hold.toml").write_text(
        HOLD.read_text().replace("duration_s = 1800.0", "duration_s = 5.0")
    )
    batch = cp.batch(str(folder), tmp_path / "b")
    assert [row["case"] for row in batch.rows] == ["hold"]


def test_results_print_short_and_summaries_are_plain_data() -> None:
    problem = cp.load(HOLD, {"simulation.duration_s": 5.0})
    run = cp.simulate(problem)
    for shown in (problem, cp.solve(problem), run):
        assert len(repr(shown)) < 300
    assert json.dumps(run.summary(), allow_nan=False)
