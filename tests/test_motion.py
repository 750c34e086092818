"""Recorded motion: joint-angle files read, repaired and replayed (casadi-posture evaluate)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import casadi_posture as cp
from casadi_posture.cli import main
from casadi_posture.errors import ProblemError
from casadi_posture.motion.recording import Recording, between, fill_gaps, repeat, resample

ARM = "problems/holding_horizontal.toml"
STANDING = "problems/standing_wall_horizontal.toml"


def _write_csv(path: Path, header: list[str], rows: list[list[object]]) -> Path:
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)
    return path


def _arm_csv(path: Path, shoulder: list[float], elbow: list[float], dt: float = 1.0) -> Path:
    rows = [[k * dt, s, e] for k, (s, e) in enumerate(zip(shoulder, elbow, strict=True))]
    return _write_csv(path, ["time_s", "shoulder_flexion", "elbow_flexion"], rows)


@pytest.mark.parametrize(
    ("name", "sets"), [(ARM, {}), (STANDING, {"simulation.duration_s": 300.0})]
)
def test_a_simulated_timeline_replays_to_the_same_torques_loads_and_fatigue(
    name: str, sets: dict, tmp_path: Path
) -> None:
    """simulate → timeline.parquet → evaluate: the same torques, loads and fatigue to 1e-9
    and the same threshold and exhaustion events (the CSV's 10 digits to 1e-8 relative)."""
    problem = cp.load(name, sets)
    run = cp.simulate(problem)
    run.write(tmp_path / "run", figures=False, report=False)
    simulated = run.result.timeline
    for kind, tolerance in (("parquet", 1e-9), ("csv", 1e-8)):
        replayed = cp.evaluate(problem, tmp_path / "run" / f"timeline.{kind}").result
        tl = replayed.timeline
        assert replayed.solver == "recorded" and set(tl.solver) == {"recorded"}
        np.testing.assert_array_equal(tl.time, simulated.time)
        for field in ("external", "passive", "active", "load", "fatigue"):
            a, b = getattr(simulated, field), getattr(tl, field)
            scale = 1.0 if kind == "parquet" else max(1.0, float(np.abs(a).max()))
            assert np.abs(a - b).max() <= tolerance * scale, (kind, field)
        # every level but a comfort level the whole-body adjustment weighs by fatigue
        np.testing.assert_allclose(tl.residuals[:, :2], simulated.residuals[:, :2], atol=1e-7)
        kinds = {"fatigue_threshold", "recovery_threshold", "exhausted"}
        want = [(e.time_s, e.kind, e.half_joint) for e in run.result.events if e.kind in kinds]
        got = [(e.time_s, e.kind, e.half_joint) for e in replayed.events]
        assert got == want


def test_fill_gaps_is_linear_inside_and_nearest_at_the_ends() -> None:
    time = np.arange(10.0) * 0.1
    values = 3.0 * time + 1.0
    holed = values.copy()
    holed[[0, 3, 4, 8]] = math.nan
    filled, short, long = fill_gaps(holed, time, max_gap_s=0.3)
    np.testing.assert_allclose(filled[1:9], values[1:9], atol=1e-12)
    assert filled[0] == values[1]  # nothing before: the nearest frame's value
    assert short == [(0, 0), (3, 4), (8, 8)] and long == []
    _, short, long = fill_gaps(holed, time, max_gap_s=0.25)
    assert (3, 4) in long and (8, 8) in short


def test_resample_and_repeat() -> None:
    """A linear motion resampled stays on its line; repeated cycles restart a step apart."""
    time = np.array([0.0, 0.5, 2.0, 3.0])
    q = np.column_stack([time * 0.1, -time])
    recording = Recording(Path("m.csv"), "angles", time, q)
    fine = resample(recording, 0.25)
    np.testing.assert_allclose(fine.time, np.arange(13) * 0.25)
    np.testing.assert_allclose(fine.q[:, 0], fine.time * 0.1, atol=1e-15)
    step = float(np.median(np.diff(time)))  # 1.0
    twice = repeat(recording, times=2)
    np.testing.assert_allclose(twice.time[4:], time + 3.0 + step)
    np.testing.assert_array_equal(twice.q[4:], q)
    until = repeat(recording, until_s=6.0)
    assert until.time[-1] <= 6.0 < until.time[-1] + 1.0 and "repeated" in until.notes[-1]
    with pytest.raises(ProblemError, match="--resample"):
        resample(recording, 10.0)


def test_between_keeps_one_phase_with_its_loads_and_residuals() -> None:
    """The frames in the window, by the file's time, with their held loads and fit
    residuals; a window with fewer than 2 frames, or backwards, is a one-line error."""
    time = np.arange(6) * 0.5
    q = np.column_stack([time, -time])
    held = np.array([[0], [1], [1], [1], [0], [0]])
    fit = {"elbow_r": time * 1e-3}
    recording = Recording(Path("m.c3d"), "c3d", time, q, held=held, residuals=fit)
    phase = between(recording, 0.5, 1.5)
    np.testing.assert_array_equal(phase.time, [0.5, 1.0, 1.5])
    np.testing.assert_array_equal(phase.q[:, 1], [-0.5, -1.0, -1.5])
    np.testing.assert_array_equal(phase.held[:, 0], [1, 1, 1])
    np.testing.assert_array_equal(phase.residuals["elbow_r"], [5e-4, 1e-3, 1.5e-3])
    assert "3 of 6" in phase.notes[-1]
    for start, end in ((1.1, 1.4), (2.0, 1.0), (math.nan, 1.0)):
        with pytest.raises(ProblemError, match="--between"):
            between(recording, start, end)


def test_a_recording_s_loads_are_its_own(tmp_path: Path) -> None:
    """The arm held at 90° shoulder flexion then dropped to hanging: the load and the
    recovery follow the frames (the hanging arm carries nothing of the shoulder flexors)."""
    shoulder = [90.0] * 200 + [0.0] * 400
    path = _arm_csv(tmp_path / "m.csv", shoulder, [0.0] * 600)
    run = cp.evaluate(cp.load(ARM), path)
    summary = run.summary()
    k = next(
        i for i, g in enumerate(summary["half_joints"]) if g["half_joint"] == "shoulder_flexors"
    )
    group = summary["half_joints"][k]
    tl = run.result.timeline
    assert tl.load[0, k] == pytest.approx(group["peak_load_pct_mvc"])
    assert tl.load[-1, k] == pytest.approx(0.0, abs=1e-9)
    held = tl.load[0, k] * 199 + tl.load[199, k] / 2 * 1 + tl.load[200, k] / 2
    assert group["mean_load_pct_mvc"] == pytest.approx(held / 599, rel=1e-9)
    assert tl.fatigue[-1, k] < tl.fatigue[199, k]  # recovers once the arm hangs
    assert summary["recording"]["frames"] == 600 and summary["task"]["recorded"]


@pytest.mark.parametrize(
    ("header", "rows", "message"),
    [
        (["t", "shoulder_flexion", "elbow_flexion"], [[0, 1, 2], [1, 1, 2]], "time_s"),
        (["time_s", "shoulder_flexion"], [[0, 10], [1, 20]], "elbow_flexion"),
        (
            ["time_s", "shoulder_flexion", "elbow_flexon"],
            [[0, 10, 20], [1, 10, 20]],
            "did you mean",
        ),
        (["time_s", "shoulder_flexion", "elbow_flexion"], [[0, 10, 20], [0, 10, 20]], "frame 2"),
        (["time_s", "shoulder_flexion", "elbow_flexion"], [[0, 10, "x"], [1, 10, 20]], "frame 1"),
        (["time_s", "shoulder_flexion", "elbow_flexion"], [[0, 10, 20]], "two frames"),
    ],
)
def test_bad_files_are_one_line_errors_with_exit_2(
    header: list[str], rows: list[list[object]], message: str, tmp_path: Path
) -> None:
    path = _write_csv(tmp_path / "m.csv", header, rows)
    result = CliRunner().invoke(
        main, ["evaluate", ARM, "--motion", str(path), "--out", str(tmp_path / "o")]
    )
    assert result.exit_code == 2, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and message in lines[0]
    assert "Traceback" not in result.output


def test_angles_in_another_unit_are_refused_and_a_tiny_step_too(tmp_path: Path) -> None:
    """Angles × 1000 (millidegrees) are refused at the first one beyond a turn (the passive
    torques overflowed and the report ended in an internal error); a --resample step of
    5e-324 s asks for more frames than the limit (an OverflowError before). A turn itself
    is still read: flagged outside the body's range, every number finite."""
    out = str(tmp_path / "out")
    milli = _arm_csv(tmp_path / "milli.csv", [0.0, 45000.0], [90000.0, 90000.0])
    result = CliRunner().invoke(main, ["evaluate", ARM, "--motion", str(milli), "--out", out])
    assert result.exit_code == 2, result.output
    expected = "expected an angle in degrees within ±360° (another unit?)"
    assert (
        result.stderr.strip() == f"error: {milli}: shoulder_flexion (frame 2) = 45000.0: {expected}"
    )
    good = _arm_csv(tmp_path / "arm.csv", [0.0, 360.0], [90.0, -360.0])
    args = ["evaluate", ARM, "--motion", str(good), "--out", out, "--force", "--no-report"]
    result = CliRunner().invoke(main, [*args, "--resample", "5e-324"])
    assert result.exit_code == 2, result.output
    expected = "expected at most 100000 frames: a longer step (the recording is 1 s)"
    assert result.stderr.strip() == f"error: {good}: --resample = 5e-324: {expected}"
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 1 and "outside the body's range" in result.output, result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(), parse_constant=float)
    assert all(math.isfinite(g["peak_load_pct_mvc"]) for g in summary["half_joints"])


def test_radians_are_refused(tmp_path: Path) -> None:
    problem = cp.load(STANDING)
    names = problem.body.dof_names
    rows = [[k, *[0.3 * math.sin(k + i) for i in range(len(names))]] for k in range(5)]
    path = _write_csv(tmp_path / "m.csv", ["time_s", *names], rows)
    with pytest.raises(ProblemError, match="looks like radians"):
        cp.evaluate(problem, path)


def test_gaps_are_filled_counted_and_long_ones_flagged(tmp_path: Path) -> None:
    shoulder = [45.0] * 20
    elbow: list[object] = [30.0] * 20
    elbow[3] = ""  # 0.2 s between the frames around it: filled and counted
    for k in range(8, 14):
        elbow[k] = ""  # 0.7 s between the frames around it: above max_gap_s, flagged
    path = _arm_csv(tmp_path / "m.csv", shoulder, elbow, dt=0.1)  # type: ignore[arg-type]
    recording = cp.read_motion(cp.load(ARM), path)
    assert any("1 gap(s)" in n for n in recording.notes)
    assert len(recording.flags) == 1 and "frames 9-14" in recording.flags[0]
    run = cp.evaluate(cp.load(ARM), recording)
    assert recording.flags[0] in run.summary()["flags"]


def test_angles_outside_the_range_are_flagged_and_missing_dofs_can_be_held(
    tmp_path: Path,
) -> None:
    path = _arm_csv(tmp_path / "m.csv", [45.0, 200.0], [30.0, 30.0])
    recording = cp.read_motion(cp.load(ARM), path)
    assert any("outside the body's range" in f for f in recording.flags)
    path = _write_csv(tmp_path / "s.csv", ["time_s", "elbow_flexion"], [[0, 30], [1, 40]])
    problem = cp.load(ARM, {"motion.hold_missing": True, "posture_deg.shoulder_flexion": 20.0})
    recording = cp.read_motion(problem, path)
    np.testing.assert_allclose(np.degrees(recording.q[:, 0]), 20.0)
    assert any("held at the problem's posture" in n for n in recording.notes)


def test_mapped_columns(tmp_path: Path) -> None:
    path = _write_csv(tmp_path / "m.csv", ["time", "SHO", "ELB"], [[0, 10, 20], [1, 15, 25]])
    problem = cp.load(ARM, {"motion.columns": {"SHO": "shoulder_flexion", "ELB": "elbow_flexion"}})
    recording = cp.read_motion(problem, path)
    np.testing.assert_allclose(np.degrees(recording.q), [[10, 20], [15, 25]])
    wrong = cp.load(ARM, {"motion.columns": {"SHO": "shoulder_flexon"}})
    with pytest.raises(ProblemError, match=r"motion\.columns\.SHO"):
        cp.read_motion(wrong, path)


def test_the_command_writes_the_run_s_files(tmp_path: Path) -> None:
    path = _arm_csv(tmp_path / "m.csv", [90.0] * 30, [0.0] * 30, dt=0.5)
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["evaluate", ARM, "--motion", str(path), "--repeat", "3", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "90 frames, 0 to 44.5 s" in result.output
    for name in ("timeline.csv", "summary.json", "events.csv", "report.html", "fatigue.png"):
        assert (out / name).exists()


def test_compare_prediction_sets_the_recording_beside_the_model(tmp_path: Path) -> None:
    """A simulated hold with the elbow 10° more flexed throughout, as if recorded: beside
    the prediction, the elbow differs by 10° RMS, the shoulder by 0; the predicted outcomes
    are simulate's own."""
    problem = cp.load(ARM)
    run = cp.simulate(problem)
    tl = run.result.timeline
    shoulder, elbow = np.degrees(tl.q[:, 0]), np.degrees(tl.q[:, 1]) + 10.0
    path = _arm_csv(tmp_path / "m.csv", shoulder.tolist(), elbow.tolist())
    out = tmp_path / "out"
    result = CliRunner().invoke(
        main, ["evaluate", ARM, "--motion", str(path), "--out", str(out), "--compare-prediction"]
    )
    assert result.exit_code in (0, 1), result.output
    assert "recorded beside predicted" in result.output
    rows = {r["dof"]: r for r in csv.DictReader((out / "prediction.csv").open())}
    assert float(rows["elbow_flexion"]["rms_difference_deg"]) == pytest.approx(10.0, rel=1e-6)
    assert float(rows["shoulder_flexion"]["rms_difference_deg"]) == pytest.approx(0.0, abs=1e-6)
    outcomes = {
        r["outcome"]: r for r in json.loads((out / "prediction.json").read_text())["outcomes"]
    }
    held = run.summary()["task"]["held_s"]
    assert outcomes["task held (s)"]["predicted"] == pytest.approx(held)
    assert (out / "predicted" / "summary.json").exists()
    (out / "predicted" / "notes.txt").write_text("mine")
    again = ["evaluate", ARM, "--motion", str(path), "--out", str(out), "--force"]
    assert CliRunner().invoke(main, again).exit_code in (0, 1)
    assert not (out / "prediction.csv").exists() and not (out / "prediction.json").exists()
    assert [p.name for p in (out / "predicted").iterdir()] == ["notes.txt"]  # only the user's


def test_a_load_held_only_in_its_window(tmp_path: Path) -> None:
    """Frames that do not hold the load carry the arm alone: their loads, compression-free
    arm and RULA load score are those of the same problem with the load's mass set to 0."""
    problem = cp.load(ARM)
    q = np.radians(np.tile([60.0, 30.0], (6, 1)))
    held = np.array([[1.0], [1.0], [0.0], [0.0], [1.0], [1.0]])
    recording = Recording(Path("m.csv"), "angles", np.arange(6.0), q, held=held)
    run = cp.evaluate(problem, recording)
    tl = run.result.timeline
    unloaded = cp.torques(
        cp.load(ARM, {"loads[0].mass_kg": 0.0}), {"shoulder_flexion": 60.0, "elbow_flexion": 30.0}
    )
    loaded = cp.torques(problem, {"shoulder_flexion": 60.0, "elbow_flexion": 30.0})
    for k, group in enumerate(g.name for g in unloaded.groups):
        expected = [loaded.groups[k].load_pct_mvc] * 2 + [unloaded.groups[k].load_pct_mvc] * 2
        np.testing.assert_allclose(tl.load[:4, k], expected, rtol=1e-12, err_msg=group)
    columns = run.to_frame()
    assert list(columns[f"held_{problem.loads[0].name}"]) == [1, 1, 0, 0, 1, 1]


def test_the_low_back_and_scores_follow_the_held_loads() -> None:
    """The seated worker's L5/S1 compression and RULA per frame: with the part, as the static
    answer with it; without, as the static answer of the problem without it."""
    name = "problems/seated_assembly.toml"
    problem = cp.load(name)
    q = np.tile(problem.posture, (4, 1))
    held = np.array([[1.0], [0.0], [0.0], [1.0]])
    run = cp.evaluate(problem, Recording(Path("m.csv"), "angles", np.arange(4.0), q, held=held))
    frame = run.to_frame()
    with_part = cp.torques(problem)
    without = cp.torques(cp.load(name, {"loads[0].mass_kg": 0.0}))
    expected = [with_part.low_back.compression, without.low_back.compression]
    np.testing.assert_allclose(frame["compression_N"][:2], expected, rtol=1e-12)
    rula = [with_part.scores[0].rula.grand, without.scores[0].rula.grand]
    assert list(frame["rula_r"][:2]) == rula


def test_a_problem_without_tasks_evaluates_and_draws(tmp_path: Path) -> None:
    """A recording needs no task: the files and every figure are written, the effector
    figure showing the joint angles that move most, and no level residual is claimed."""
    import tomllib

    data = tomllib.loads(Path(ARM).read_text())
    del data["tasks"]
    problem = cp.from_dict(data, "no_tasks.toml")
    path = _arm_csv(tmp_path / "m.csv", [10.0, 40.0, 70.0], [5.0, 25.0, 45.0])
    run = cp.evaluate(problem, path)
    written = run.write(tmp_path / "out")
    assert (tmp_path / "out" / "effector.png") in written
    task = run.summary()["task"]
    assert task["level1"] is None and task["held_s"] == 2.0
    assert "task residuals" in (tmp_path / "out" / "report.html").read_text()


def test_rerun_repeats_an_evaluation_and_refuses_a_changed_recording(tmp_path: Path) -> None:
    """rerun on evaluate's manifest reads the same recording the same way (--between and
    --repeat here: 5 frames twice)
    and gives summary.json byte for byte; a recording changed since is a one-line error."""
    path = _arm_csv(tmp_path / "m.csv", [90.0] * 10, [0.0] * 10)
    out = tmp_path / "out"
    command = ["evaluate", ARM, "--motion", str(path), "--repeat", "2", "--out", str(out)]
    assert CliRunner().invoke(main, [*command, "--between", "2", "6"]).exit_code == 0
    again = CliRunner().invoke(main, ["rerun", str(out / "manifest.json")])
    assert again.exit_code == 0, again.output
    assert "summary.json identical to" in again.output and "10 frames" in again.output
    _arm_csv(path, [80.0] * 10, [0.0] * 10)
    changed = CliRunner().invoke(
        main, ["rerun", str(out / "manifest.json"), "--out", str(tmp_path / "r2")]
    )
    assert changed.exit_code == 2 and "the recording as it was" in changed.output


def test_compare_prediction_without_tasks_is_refused_before_anything_runs(tmp_path: Path) -> None:
    import tomllib

    data = tomllib.loads(Path(ARM).read_text())
    file = tmp_path / "no_tasks.toml"
    text = Path(ARM).read_text()
    file.write_text(text[: text.index("[[tasks]]")] + text[text.index("[fatigue]") :])
    assert "tasks" in data and "tasks" not in tomllib.loads(file.read_text())
    path = _arm_csv(tmp_path / "m.csv", [10.0, 20.0], [5.0, 5.0])
    out = tmp_path / "out"
    command = ["evaluate", str(file), "--motion", str(path), "--out", str(out)]
    result = CliRunner().invoke(main, [*command, "--compare-prediction"])
    assert result.exit_code == 2 and "at least one task" in result.output
    assert not out.exists()
