"""A population on a real Dask cluster: a scheduler and two workers as processes of their
own on the loopback address, one worker killed while the run goes on."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")

PROBLEM = "problems/standing_wall_horizontal.toml"
ARGS = ["--n", "4", "--seed", "5", "--set", "simulation.duration_s=60", "--quiet"]
BIN = Path(sys.executable).parent


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _population(out: Path, *extra: str) -> subprocess.Popen:
    command = [str(BIN / "casadi-posture"), "population", PROBLEM, *ARGS, "--out", str(out)]
    return subprocess.Popen([*command, *extra], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


def _finished(out: Path) -> int:
    cases = out / "cases"
    return sum((p / "row.json").exists() for p in cases.iterdir()) if cases.exists() else 0


@pytest.mark.slow
def test_a_killed_worker_loses_nothing_and_resume_gives_the_local_numbers(tmp_path: Path) -> None:
    """8 workers (4 per sex) on a scheduler with two worker processes; one worker is
    killed (SIGKILL) once the first case is finished. The scheduler gives its tasks to the
    other: every case ends once, none failed, and --resume then runs nothing; the
    population.json is byte for byte a local run's (--jobs 1)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    logs = tmp_path / "logs"
    logs.mkdir()
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    scheduler = subprocess.Popen(
        [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port),
         "--dashboard-address", ":0"],
        stdout=(logs / "scheduler.log").open("w"), stderr=subprocess.STDOUT, env=env,
    )  # fmt: skip
    workers = [
        subprocess.Popen(
            [
                str(BIN / "dask"),
                "worker",
                address,
                "--nthreads",
                "1",
                "--nworkers",
                "1",
                "--memory-limit",
                "0",
                "--no-nanny",
                "--dashboard-address",
                ":0",
            ],
            stdout=(logs / f"worker{k}.log").open("w"),
            stderr=subprocess.STDOUT,
            env=env,
        )
        for k in range(2)
    ]
    try:
        out = tmp_path / "dask"
        run = _population(out, "--scheduler", address)
        deadline = time.monotonic() + 240
        while _finished(out) < 1 and run.poll() is None and time.monotonic() < deadline:
            time.sleep(0.2)
        assert run.poll() is None, run.communicate()[0].decode()
        workers[0].send_signal(signal.SIGKILL)
        output = run.communicate(timeout=300)[0].decode()
        assert _finished(out) == 8, output
        rows = [json.loads((p / "row.json").read_text()) for p in (out / "cases").iterdir()]
        assert sorted(r["case"] for r in rows) == sorted(
            f"{sex}-{k:04d}" for sex in ("male", "female") for k in range(4)
        )
        assert {r["status"] for r in rows} <= {"ok", "flagged"}
        again = _population(out, "--scheduler", address, "--resume")
        assert "0 run now, 8 already done" in again.communicate(timeout=300)[0].decode()
    finally:
        for process in [*workers, scheduler]:
            process.kill()
            process.wait()
    local = tmp_path / "local"
    assert _population(local, "--jobs", "1").wait(timeout=300) in (0, 1)
    assert (local / "population.json").read_bytes() == (out / "population.json").read_bytes()
