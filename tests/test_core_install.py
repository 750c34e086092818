"""Every core command on the core install: the optional extras hidden (tests/core_only.py),
each command runs and writes its files, and a feature that needs an extra says which in one
line (exit 2)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import PROBLEMS

CORE_ONLY = Path(__file__).with_name("core_only.py")
HOLDING = str(PROBLEMS / "holding_m45.toml")
#: A one-minute hold, for the commands that run a grid or many files.
SHORT = ("--set", "simulation.duration_s=60")


def core(*args: str | Path, hide_also: str = "") -> subprocess.CompletedProcess[str]:
    """``casadi-posture ARGS`` with the optional extras (and ``hide_also``) hidden."""
    command = [sys.executable, str(CORE_ONLY), *map(str, args)]
    env = os.environ | {"HIDE_ALSO": hide_also}
    return subprocess.run(command, capture_output=True, text=True, timeout=300, env=env)


def ran(done: subprocess.CompletedProcess[str]) -> None:
    """The command ran to an answer (flagged or not), without an internal error."""
    assert done.returncode in (0, 1), done.stderr
    assert "internal error" not in done.stdout + done.stderr
    assert "Traceback" not in done.stderr


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``simulate`` of the −45° hold on the core install, with every figure and the page."""
    out = tmp_path_factory.mktemp("core") / "simulate"
    ran(core("simulate", HOLDING, "--duration", "120", "--out", out))
    return out


def test_simulate_writes_every_file_but_parquet(run: Path) -> None:
    written = {p.name for p in run.iterdir()}
    assert {"timeline.csv", "events.csv", "summary.json", "manifest.json"} <= written
    assert {"postures.png", "fatigue.png", "report.html"} <= written
    assert "timeline.parquet" not in written  # pyarrow is installed here, but hidden


def test_simulate_answers_as_the_full_install_does(run: Path, tmp_path: Path) -> None:
    """The timeline on the core install is, to the byte, the full install's."""
    out = tmp_path / "full"
    full = subprocess.run(
        [
            sys.executable,
            "-m",
            "casadi_posture",
            "simulate",
            HOLDING,
            "--duration",
            "120",
            "--out",
            str(out),
            "--no-figures",
            "--no-report",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert full.returncode == 0, full.stderr
    assert (out / "timeline.parquet").exists()
    assert (out / "timeline.csv").read_bytes() == (run / "timeline.csv").read_bytes()


@pytest.mark.parametrize(
    ("args", "written"),
    [
        (("solve", PROBLEMS / "standing_wall_horizontal.toml"), "solve.json"),
        (("whatif", HOLDING, "--vary", "loads[0].mass_kg=1,2", *SHORT), "whatif.csv"),
        (("batch", HOLDING, PROBLEMS / "holding_m25.toml", *SHORT), "summary.csv"),
        (("duty-cycle", HOLDING, "--t-off", "30", "--horizon", "10min"), "duty_cycle.json"),
        (("population", HOLDING, "--n", "1", "--jobs", "1"), "population.json"),
        (("sensitivity", HOLDING), "sensitivity.json"),
        (("compare", HOLDING), "compare.csv"),
    ],
    ids=lambda a: a[0] if isinstance(a, tuple) else None,
)
def test_core_command_writes_its_files(args: tuple, written: str, tmp_path: Path) -> None:
    out = tmp_path / "out"
    ran(core(*args, "--out", out))
    assert (out / written).is_file()
    assert not list(out.rglob("*.parquet"))


def test_evaluate_and_rerun_a_joint_angle_recording(run: Path, tmp_path: Path) -> None:
    """The simulated timeline, read back as a recording of joint angles (CSV), then the
    evaluation repeated from its manifest."""
    out = tmp_path / "evaluate"
    ran(core("evaluate", HOLDING, "--motion", run / "timeline.csv", "--out", out))
    assert (out / "summary.json").is_file()
    again = core("rerun", out / "manifest.json", "--out", tmp_path / "again")
    ran(again)
    assert "identical" in again.stdout


@pytest.mark.parametrize(
    ("args", "extra"),
    [
        (
            (
                "evaluate",
                PROBLEMS / "recorded_box_transfer.toml",
                "--motion",
                PROBLEMS / "recordings" / "box_transfer.c3d",
            ),
            "motion",
        ),
        (("population", HOLDING, "--n", "1", "--scheduler", "tcp://127.0.0.1:1"), "dask"),
    ],
    ids=["c3d", "scheduler"],
)
def test_a_feature_of_an_extra_names_it(args: tuple, extra: str, tmp_path: Path) -> None:
    done = core(*args, "--out", tmp_path / "out")
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.count("\n") == 1
    assert f"casadi_posture[{extra}]" in done.stderr


def test_a_process_writing_the_files_names_what_failed_it(tmp_path: Path) -> None:
    """The process that writes a run's files cannot import matplotlib: the command says
    so, not that the process "ended abruptly"."""
    done = core("simulate", HOLDING, "--duration", "10", "--out", tmp_path, hide_also="matplotlib")
    assert done.returncode != 0
    assert "No module named 'matplotlib'" in done.stderr
    assert "abruptly" not in done.stderr
