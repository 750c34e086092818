"""Batch runs and what-if grids: failures recorded, resumable after a kill, independent of
the number of jobs, on a Dask cluster too; endurance falls as the load grows."""

from __future__ import annotations

import csv
import itertools
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture.cli import main
from casadi_posture.runs import batch

HOLD = (PROBLEMS / "holding_m45.toml").read_text()


def run(*args: str):
    return CliRunner().invoke(main, list(args))


def _problems(folder: Path, count: int, duration: float, *, bad: bool = False) -> Path:
    """``count`` variants of the -45° hold with loads 1, 1.5, 2, ... kg, ``duration`` s."""
    folder.mkdir()
    for i in range(count):
        text = HOLD.replace("mass_kg = 2.5", f"mass_kg = {1.0 + 0.5 * i}")
        text = text.replace("duration_s = 1800.0", f"duration_s = {duration}")
        (folder / f"case{i}.toml").write_text(text)
    if bad:
        (folder / "broken.toml").write_text(HOLD.replace("mass_kg = 73.0", "mass_kg = -5.0"))
    return folder


def _summary(out: Path) -> list[dict[str, str]]:
    with (out / "summary.csv").open() as handle:
        return list(csv.DictReader(handle))


def test_a_bad_case_is_recorded_and_the_batch_carries_on(tmp_path: Path) -> None:
    folder = _problems(tmp_path / "in", 2, 30.0, bad=True)
    result = run("batch", str(folder), "--out", str(tmp_path / "out"), "--solver", "nullspace")
    assert result.exit_code == 1, result.output
    rows = {r["case"]: r for r in _summary(tmp_path / "out")}
    assert rows["broken"]["status"] == "failed"
    assert "body.mass_kg = -5.0" in rows["broken"]["error"]
    assert rows["case0"]["status"] == rows["case1"]["status"] == "ok"
    assert (tmp_path / "out" / "cases" / "broken" / "failure.json").exists()
    assert (tmp_path / "out" / "cases" / "case0" / "timeline.csv").exists()
    assert "failed broken" in result.stdout


def test_jobs_1_and_2_give_identical_summaries(tmp_path: Path) -> None:
    folder = _problems(tmp_path / "in", 3, 60.0)
    for jobs in ("1", "2"):
        result = run(
            "batch",
            str(folder),
            "--out",
            str(tmp_path / f"jobs{jobs}"),
            "--jobs",
            jobs,
            "--solver",
            "nullspace",
            "--quiet",
        )
        assert result.exit_code == 0, result.output
    one = (tmp_path / "jobs1" / "summary.csv").read_bytes()
    assert one == (tmp_path / "jobs2" / "summary.csv").read_bytes()
    assert len(_summary(tmp_path / "jobs1")) == 3


def test_parquet_summary_matches_the_csv(tmp_path: Path) -> None:
    pq = pytest.importorskip("pyarrow.parquet")
    folder = _problems(tmp_path / "in", 2, 30.0)
    assert run("batch", str(folder), "--out", str(tmp_path / "out"), "--quiet").exit_code == 0
    table = pq.read_table(tmp_path / "out" / "summary.parquet").to_pylist()
    assert [r["case"] for r in table] == [r["case"] for r in _summary(tmp_path / "out")]
    assert table[0]["limiting_group_at_start"] == "shoulder_flexors"


def test_a_killed_batch_resumes_without_redoing_or_losing_cases(tmp_path: Path) -> None:
    folder = _problems(tmp_path / "in", 8, 200.0)
    out = tmp_path / "out"
    command = [
        sys.executable,
        "-m",
        "casadi_posture",
        "batch",
        str(folder),
        "--out",
        str(out),
        "--solver",
        "lexicographic",
        "--quiet",
    ]
    process = subprocess.Popen(command, start_new_session=True)
    cases = out / "cases"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        finished = [p for p in cases.glob("case*") if p.is_dir()] if cases.exists() else []
        if len(finished) >= 2:
            break
        time.sleep(0.02)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    before = {p.name: (p / "row.json").stat().st_mtime_ns for p in cases.glob("case*")}
    assert 2 <= len(before) < 8, "the kill must land mid-batch"
    assert not (out / "summary.csv").exists()
    resumed = subprocess.run([*command, "--resume"], capture_output=True, text=True, check=False)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{8 - len(before)} run now, {len(before)} already done" in resumed.stdout
    after = {p.name: (p / "row.json").stat().st_mtime_ns for p in cases.glob("case*")}
    assert len(after) == 8
    assert all(after[name] == stamp for name, stamp in before.items())
    assert not list(cases.glob(".tmp-*"))
    for case in cases.iterdir():
        assert {"row.json", "timeline.csv", "summary.json", "fatigue.png"} <= {
            p.name for p in case.iterdir()
        }
    assert len(_summary(out)) == 8


def test_an_existing_batch_needs_resume(tmp_path: Path) -> None:
    folder = _problems(tmp_path / "in", 1, 30.0)
    out = tmp_path / "out"
    assert run("batch", str(folder), "--out", str(out), "--quiet").exit_code == 0
    again = run("batch", str(folder), "--out", str(out), "--quiet")
    assert again.exit_code == 2 and "--resume" in again.stderr
    assert len(again.stderr.strip().splitlines()) == 1


def test_endurance_falls_as_the_load_grows(tmp_path: Path) -> None:
    static = run(
        "whatif",
        str(PROBLEMS / "holding_m45.toml"),
        "--vary",
        "loads[0].mass_kg=0.5,1,2,4,8",
        "--static",
        "--out",
        str(tmp_path / "s"),
        "--quiet",
    )
    assert static.exit_code == 0, static.output
    rows = sorted(_summary(tmp_path / "s"), key=lambda r: float(r["loads[0].mass_kg"]))
    endurance = [float(r["limiting_endurance_at_start_min"]) for r in rows]
    assert all(b < a for a, b in itertools.pairwise(endurance))
    simulated = run(
        "whatif",
        str(PROBLEMS / "holding_m45.toml"),
        "--vary",
        "loads[0].mass_kg=1,2.5,5",
        "--solver",
        "nullspace",
        "--out",
        str(tmp_path / "t"),
        "--quiet",
    )
    assert simulated.exit_code == 0, simulated.output
    rows = sorted(_summary(tmp_path / "t"), key=lambda r: float(r["loads[0].mass_kg"]))
    first = [float(r["first_fatigue_s"]) for r in rows]
    held = [float(r["task_held_s"]) for r in rows]
    assert first[0] > first[1] > first[2] and held[0] > held[1] > held[2]
    assert (tmp_path / "t" / "whatif.csv").exists()
    assert (tmp_path / "t" / "whatif_task_held_s_vs_loads_0_.mass_kg.png").exists()
    assert "shoulder_flexors" in simulated.stdout


def test_whatif_varies_strings_and_the_solver(tmp_path: Path) -> None:
    result = run(
        "whatif",
        str(PROBLEMS / "strategy_frontal_elbow.toml"),
        "--vary",
        "fatigue.strategy=active,passive",
        "--vary",
        "solver=nullspace,lexicographic",
        "--out",
        str(tmp_path),
        "--quiet",
    )
    assert result.exit_code == 0, result.output
    rows = _summary(tmp_path)
    assert {(r["fatigue.strategy"], r["solver"]) for r in rows} == {
        ("active", "nullspace"),
        ("active", "lexicographic"),
        ("passive", "nullspace"),
        ("passive", "lexicographic"),
    }
    by = {(r["fatigue.strategy"], r["solver"]): r for r in rows}
    assert float(by["active", "nullspace"]["recovery_elbow_flexion_deg"]) == pytest.approx(
        float(by["active", "lexicographic"]["recovery_elbow_flexion_deg"]), abs=0.01
    )


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--vary", "loads[0].mass_kg"], "--vary"),
        (["--vary", "loads[0].mass_kg=1,,2"], "no empty value"),
        (["--vary", "loads[0].mass_kg=-1"], "loads[0].mass_kg = -1"),
    ],
)
def test_bad_whatif_input(tmp_path: Path, args: list[str], needle: str) -> None:
    result = run(
        "whatif", str(PROBLEMS / "holding_m45.toml"), *args, "--static", "--out", str(tmp_path)
    )
    assert result.exit_code == 2, result.output
    assert needle in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_an_unreachable_scheduler_is_a_usage_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(batch, "CONNECT_S", 2.0)  # the same refusal, sooner than 20 s
    folder = _problems(tmp_path / "in", 1, 30.0)
    result = run(
        "batch",
        str(folder),
        "--out",
        str(tmp_path / "out"),
        "--scheduler",
        "tcp://127.0.0.1:1",
        "--quiet",
    )
    assert result.exit_code == 2 and "--scheduler" in result.stderr


def test_a_dask_cluster_gives_the_local_summary(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    folder = _problems(tmp_path / "in", 3, 60.0)
    local = run(
        "batch", str(folder), "--out", str(tmp_path / "local"), "--solver", "nullspace", "--quiet"
    )
    assert local.exit_code == 0, local.output
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        remote = run(
            "batch",
            str(folder),
            "--out",
            str(tmp_path / "dask"),
            "--solver",
            "nullspace",
            "--scheduler",
            cluster.scheduler_address,
            "--quiet",
        )
    assert remote.exit_code == 0, remote.output
    assert (tmp_path / "local" / "summary.csv").read_bytes() == (
        tmp_path / "dask" / "summary.csv"
    ).read_bytes()


def test_a_case_runs_from_its_text_where_the_file_does_not_exist() -> None:
    """What a remote worker sees: the problem's text, and a path that means nothing there."""
    from casadi_posture.runs.batch import Case, run_case

    text = HOLD.replace("duration_s = 1800.0", "duration_s = 20.0")
    outcome = run_case(
        Case("remote", "/nowhere/holding.toml", {"loads[0].mass_kg": 5.0}, "nullspace", True, text)
    )
    assert outcome.row["status"] == "ok", outcome.row["error"]
    assert outcome.row["loads[0].mass_kg"] == 5.0
    assert {"timeline.csv", "summary.json", "fatigue.png"} <= set(outcome.files)
    missing = run_case(Case("gone", "/nowhere/holding.toml"))
    assert missing.row["status"] == "failed" and "does not exist" in missing.row["error"]


def test_simulated_and_static_cases_agree_on_the_start_posture() -> None:
    """A simulated case reads its start outcomes from the simulation's first step; they must
    be what the static path computes from the torques at the solved start posture."""
    from casadi_posture.runs.batch import Case, run_case

    text = HOLD.replace("duration_s = 1800.0", "duration_s = 5.0")
    simulated = run_case(Case("s", "holding.toml", {}, "nullspace", True, text)).row
    static = run_case(Case("t", "holding.toml", {}, "nullspace", False, text)).row
    keys = [k for k in static if k.startswith(("initial_", "limiting_endurance", "residual"))]
    assert len(keys) == 10
    for key in keys:
        assert simulated[key] == pytest.approx(static[key], rel=1e-9), key
    assert simulated["limiting_group_at_start"] == static["limiting_group_at_start"]
    assert static["limiting_group_at_start"] == "shoulder_flexors"
    assert simulated["reached"] is static["reached"] is True
