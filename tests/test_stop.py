"""Stopping and resuming: Ctrl-C on real processes, resuming only the same run, retrying
failed cases, skipping problems without tasks."""

from __future__ import annotations

import csv
import json
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

#: Ctrl-C must stop a run within this [s], files written included: a simulation stopped
#: after thousands of steps writes their timeline and figures (1.5-2.2 s measured with the
#: test suite running beside it, up to 3.1 s with two busy processes on the 2 cores). A
#: Ctrl-C left unheard would take the rest of the run, over 20 s here.
STOP_WITHIN_S = 6.0

CYCLES = (PROBLEMS / "line_plane_hysteresis.toml").read_text()
HOLD = (PROBLEMS / "holding_m45.toml").read_text()


def run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


def _command(*args: object) -> list[str]:
    return [sys.executable, "-m", "casadi_posture", *map(str, args)]


def _start(command: list[str]) -> subprocess.Popen:
    """Run a command in its own process group, with Ctrl-C as a terminal's foreground job
    gets it: a suite started in the background inherits SIGINT ignored, and the command
    rightly leaves an ignored Ctrl-C alone."""
    return subprocess.Popen(
        command,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _ctrl_c(process: subprocess.Popen) -> tuple[int, float, str]:
    """Send SIGINT to the command's whole process group, as a terminal's Ctrl-C does; the
    exit code, the time it took to stop [s] and what it wrote on stderr."""
    start = time.monotonic()
    os.killpg(process.pid, signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    return process.returncode, time.monotonic() - start, stderr


def _wait_until_loading(process: subprocess.Popen, library: str) -> None:
    """Return once the process has mapped a shared library whose path names
    ``library`` (Linux's /proc; elsewhere a fixed wait): it is then inside its imports,
    whatever the machine's load, and not before the entry point could catch Ctrl-C."""
    maps = Path(f"/proc/{process.pid}/maps")
    if not maps.parent.exists():
        time.sleep(0.2)
        return
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline and process.poll() is None:
        try:
            if library in maps.read_text():
                return
        except OSError:
            pass
        time.sleep(0.002)
    raise AssertionError(f"the command never loaded {library} (exit code {process.poll()})")


def _cycles(path: Path, duration: float, mass: float = 1.0) -> Path:
    text = CYCLES.replace("duration_s = 1200.0", f"duration_s = {duration}")
    path.write_text(text.replace("mass_kg = 1.0", f"mass_kg = {mass}"))
    return path


def _live_in_group(group: int) -> list[int]:
    """Processes of a process group that are still running (zombies, already dead and
    waiting to be reaped, do not count)."""
    live = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == group and fields[0] != "Z":
            live.append(int(stat.parent.name))
    return live


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


def test_ctrl_c_stops_simulate_and_keeps_the_partial_timeline(tmp_path: Path) -> None:
    problem = _cycles(tmp_path / "long.toml", 20000.0)
    out = tmp_path / "run"
    process = _start(_command("simulate", problem, "--out", out))
    time.sleep(6.0)  # past the imports and the build, well inside the run
    code, took, stderr = _ctrl_c(process)
    assert code == 130 and took < STOP_WITHIN_S, (code, took, stderr)
    assert "Traceback" not in stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stop"] == "interrupted" and 0 < summary["simulated_s"] < 20000
    assert any(f.startswith("interrupted at") for f in summary["flags"])
    timeline = _rows(out / "timeline.csv")
    assert len(timeline) == summary["solver_statistics"]["steps"] > 1
    events = _rows(out / "events.csv")
    assert events[-1]["event"] == "interrupted"
    assert (out / "fatigue.png").exists()


def test_ctrl_c_stops_a_parallel_batch_keeping_finished_cases(tmp_path: Path) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("a0", "a1"):
        _cycles(folder / f"{name}.toml", 30.0)
    for i in range(4):
        _cycles(folder / f"b{i}.toml", 5000.0, 1.0 + 0.1 * i)
    out = tmp_path / "out"
    command = _command("batch", folder, "--out", out, "--jobs", "2", "--quiet")
    process = _start(command)
    cases = out / "cases"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not all((cases / n).is_dir() for n in ("a0", "a1")):
        time.sleep(0.05)
    time.sleep(0.5)  # the workers are inside the long cases now
    code, took, stderr = _ctrl_c(process)
    assert code == 130 and took < STOP_WITHIN_S, (code, took, stderr)
    assert "Traceback" not in stderr and "interrupted" in stderr and "--resume" in stderr
    kept = {p.name for p in cases.iterdir() if not p.name.startswith(".")}
    assert {"a0", "a1"} <= kept and len(kept) < 6
    assert not list(cases.glob(".tmp-*"))
    # Multiprocessing's resource tracker leaves once the batch's end of its pipe closes.
    deadline = time.monotonic() + STOP_WITHIN_S
    while _live_in_group(process.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = _live_in_group(process.pid)
    assert not left, f"processes outlived the batch: {left}"
    assert {r["case"] for r in _rows(out / "summary.csv")} == kept
    stamps = {n: (cases / n / "row.json").stat().st_mtime_ns for n in kept}
    # Finish the run with shorter long cases: a changed unfinished case is allowed.
    for i in range(4):
        _cycles(folder / f"b{i}.toml", 30.0, 1.0 + 0.1 * i)
    if kept & {f"b{i}" for i in range(4)}:
        return  # a long case finished before Ctrl-C; its inputs may not change (tested below)
    resumed = subprocess.run(
        [*command, "--resume"], capture_output=True, text=True, check=False, timeout=300
    )
    assert resumed.returncode == 0, resumed.stderr
    assert all((cases / n / "row.json").stat().st_mtime_ns == s for n, s in stamps.items())
    assert len(_rows(out / "summary.csv")) == 6


def test_resume_refuses_another_grid(tmp_path: Path) -> None:
    out = tmp_path / "w"
    hold = str(PROBLEMS / "holding_m45.toml")
    first = run(
        "whatif", hold, "--vary", "loads[0].mass_kg=1,2", "--static", "--quiet", "--out", out
    )
    assert first.exit_code == 0, first.output
    again = run(
        "whatif",
        hold,
        "--vary",
        "loads[0].mass_kg=1,3",
        "--static",
        "--quiet",
        "--out",
        out,
        "--resume",
    )
    assert again.exit_code == 2
    line = again.stderr.strip()
    assert len(line.splitlines()) == 1 and "--resume" in line and "different run" in line
    other = run(
        "whatif", hold, "--vary", "loads[0].mass_kg=1,2", "--quiet", "--out", out, "--resume"
    )
    assert other.exit_code == 2, "static and simulated grids are different runs"
    same = run(
        "whatif",
        hold,
        "--vary",
        "loads[0].mass_kg=1,2",
        "--static",
        "--quiet",
        "--out",
        out,
        "--resume",
    )
    assert same.exit_code == 0 and "loads[0].mass_kg" in same.output
    record = json.loads((out / "run.json").read_text())
    assert record["vary"] == {"loads[0].mass_kg": [1, 2]} and record["static"] is True
    assert record["tool"]["name"] == "casadi_posture" and len(record["problem_sha256"]) == 64


def test_resume_retries_failed_cases_and_refuses_changed_finished_ones(tmp_path: Path) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    good = HOLD.replace("duration_s = 1800.0", "duration_s = 20.0")
    (folder / "good.toml").write_text(good)
    (folder / "bad.toml").write_text(good.replace("mass_kg = 73.0", "mass_kg = -5.0"))
    out = tmp_path / "out"
    first = run("batch", folder, "--out", out, "--solver", "nullspace", "--quiet")
    assert first.exit_code == 1 and "failed bad: " in first.output
    stamp = (out / "cases" / "good" / "row.json").stat().st_mtime_ns
    (folder / "bad.toml").write_text(good)  # the user fixes the file
    fixed = run("batch", folder, "--out", out, "--solver", "nullspace", "--quiet", "--resume")
    assert fixed.exit_code == 0, fixed.output
    assert "1 run now, 1 already done" in fixed.output
    assert {r["case"]: r["status"] for r in _rows(out / "summary.csv")} == {
        "bad": "ok",
        "good": "ok",
    }
    assert (out / "cases" / "good" / "row.json").stat().st_mtime_ns == stamp
    (folder / "good.toml").write_text(good.replace("mass_kg = 2.5", "mass_kg = 3.0"))
    changed = run("batch", folder, "--out", out, "--solver", "nullspace", "--quiet", "--resume")
    assert changed.exit_code == 2 and "finished case good" in changed.stderr


def test_a_problem_without_tasks_is_skipped_not_failed(tmp_path: Path) -> None:
    folder = tmp_path / "problems"
    folder.mkdir()
    for path in PROBLEMS.glob("*.toml"):
        text = path.read_text()
        for line in text.splitlines():
            if line.startswith("duration_s"):
                text = text.replace(line, "duration_s = 20.0")
        (folder / path.name).write_text(text)
    result = run("batch", folder, "--out", tmp_path / "out", "--jobs", "2", "--quiet")
    assert "skipped frontal_elbow: no tasks to hold" in result.output
    rows = {r["case"]: r for r in _rows(tmp_path / "out" / "summary.csv")}
    without_tasks = {"frontal_elbow", "recorded_box_transfer"}  # a curve, a recording
    assert {rows[n]["status"] for n in without_tasks} == {"skipped"}
    # A skipped case neither fails the batch nor flags it.
    assert result.exit_code == 0, result.output
    assert {r["status"] for n, r in rows.items() if n not in without_tasks} == {"ok"}


def test_ctrl_c_during_startup_is_one_line() -> None:
    """Even while the libraries load, Ctrl-C ends with one line and exit code 130."""
    script = Path(sys.executable).parent / "casadi-posture"
    process = _start([str(script), "validate", str(PROBLEMS / "holding_m45.toml")])
    _wait_until_loading(process, "numpy")
    code, _, stderr = _ctrl_c(process)
    assert code == 130 and stderr.strip() == "interrupted", (code, stderr)


def test_a_whatif_over_a_problem_without_tasks_lists_its_cases_as_skipped(tmp_path: Path) -> None:
    result = run(
        "whatif",
        PROBLEMS / "frontal_elbow.toml",
        "--vary",
        "body.mass_kg=60,80",
        "--quiet",
        "--out",
        tmp_path / "w",
    )
    assert result.exit_code == 0, result.output
    assert result.output.count("skipped: no tasks to hold") == 2


def test_an_internal_error_is_one_line_unless_asked_for(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import casadi_posture.api as model

    def broken(problem):
        raise RuntimeError("unexpected\nsecond line")

    monkeypatch.setattr(model, "description", broken)
    result = run("describe", PROBLEMS / "holding_m45.toml")
    assert result.exit_code == 1
    assert result.stderr.strip().splitlines() == [
        "internal error: RuntimeError: unexpected (a bug: please report it with the command "
        "line; CASADI_POSTURE_DEBUG=1 shows the traceback)"
    ]
    monkeypatch.setenv("CASADI_POSTURE_DEBUG", "1")
    assert isinstance(run("describe", PROBLEMS / "holding_m45.toml").exception, RuntimeError)


@pytest.mark.slow
def test_ctrl_c_stops_a_population_on_every_core_and_says_its_answer_is_partial(
    tmp_path: Path,
) -> None:
    """A population runs on every core by default. Ctrl-C once a worker has finished: exit
    130, the finished workers kept, population.json marked interrupted with the count it
    holds, no process left; --resume runs the rest and the answer is whole."""
    out = tmp_path / "pop"
    problem = PROBLEMS / "standing_wall_horizontal.toml"
    command = _command("population", problem, "--n", "4", "--out", out, "--quiet")
    process = _start(command)
    cases = out / "cases"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (cases.is_dir() and any(cases.iterdir())):
        time.sleep(0.05)
    code, took, stderr = _ctrl_c(process)
    assert code == 130 and took < STOP_WITHIN_S, (code, took, stderr)
    assert "Traceback" not in stderr and "--resume" in stderr
    deadline = time.monotonic() + STOP_WITHIN_S
    while _live_in_group(process.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _live_in_group(process.pid)
    kept = [p for p in cases.iterdir() if not p.name.startswith(".")]
    partial = json.loads((out / "population.json").read_text())
    assert partial["interrupted"] is True
    assert partial["workers_total"] == 8
    assert partial["workers_finished"] == len(kept) < 8
    resumed = subprocess.run(
        [*command, "--resume"], capture_output=True, text=True, check=False, timeout=300
    )
    assert resumed.returncode == 0, resumed.stderr
    whole = json.loads((out / "population.json").read_text())
    assert whole["interrupted"] is False and whole["workers_finished"] == 8
