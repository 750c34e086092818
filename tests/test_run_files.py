"""A run's files written side by side by processes forked from this one: the same bytes as
one after the other, a job's error raised here, Ctrl-C leaving no file half written."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import PROBLEMS

from casadi_posture import api
from casadi_posture.output.run_files import side_by_side, write_run

#: The 3-D standing hold for 300 s: the constraint takes over at 244 s, so every figure
#: of a 3-D body is drawn (scores, low back, regions) with something in it.
STANDING = {"simulation.duration_s": 300.0}


@pytest.fixture(scope="module")
def standing() -> api.Simulation:
    return api.simulate(api.load(PROBLEMS / "standing_wall_horizontal.toml", STANDING))


def test_side_by_side_writes_the_same_files_as_one_after_the_other(standing, tmp_path) -> None:
    one = write_run(standing.result, tmp_path / "one", command=["x"], workers=1)
    two = write_run(standing.result, tmp_path / "two", command=["x"], workers=2)
    names = [p.name for p in one.paths]
    assert names == [p.name for p in two.paths] and one.report_missing is two.report_missing
    assert {"timeline.csv", "postures.png", "scores.png", "low_back.png", "report.html"} <= set(
        names
    )
    for a, b in zip(one.paths, two.paths, strict=True):
        if a.name != "manifest.json":  # it records when it was written
            assert a.read_bytes() == b.read_bytes(), a.name


def test_a_job_s_error_is_raised_here(tmp_path) -> None:
    def fails() -> None:
        raise ZeroDivisionError("in a worker")

    jobs = [lambda: (tmp_path / "a").write_text("a"), fails, lambda: 3]
    with pytest.raises(ZeroDivisionError, match="in a worker"):
        side_by_side(jobs, 2)
    assert side_by_side([lambda: 1, lambda: os.getpid()], 2)[1] != os.getpid()  # forked
    assert side_by_side([lambda: 1, lambda: os.getpid()], 1) == [1, os.getpid()]  # here


#: Four jobs of 1.5 s on two workers, each leaving a mark when it starts and its file when
#: it ends; the result and whether Ctrl-C was heard printed at the end.
SCRIPT = """
import sys, time
from pathlib import Path
from casadi_posture import interrupt
from casadi_posture.output.run_files import side_by_side

out = Path(sys.argv[1])

def job(k):
    def write():
        (out / f"started{k}").touch()
        time.sleep(1.5)
        (out / f"file{k}").write_text("whole")
        return k
    return write

with interrupt.deferred():
    print(side_by_side([job(k) for k in range(4)], 2), interrupt.requested(), flush=True)
"""


def _ctrl_c_while_writing(tmp_path: Path, presses: int) -> tuple[int, str, set[str]]:
    """Run SCRIPT in its own process group and press Ctrl-C ``presses`` times once the
    first jobs have started: its exit code, stdout and the files left."""
    process = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, str(tmp_path)],
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not (tmp_path / "started1").exists() and time.monotonic() < deadline:
        time.sleep(0.01)
    for _ in range(presses):
        os.killpg(process.pid, signal.SIGINT)
        time.sleep(0.1)
    stdout, _ = process.communicate(timeout=60)
    return process.returncode, stdout, {p.name for p in tmp_path.iterdir()}


def test_ctrl_c_while_writing_lets_every_file_be_written(tmp_path) -> None:
    """The terminal sends Ctrl-C to the workers too: they carry on, and this process,
    which decides, hears it."""
    code, stdout, files = _ctrl_c_while_writing(tmp_path, presses=1)
    assert code == 0 and stdout.strip() == "[0, 1, 2, 3] True"
    assert {f"file{k}" for k in range(4)} <= files
    assert all((tmp_path / f"file{k}").read_text() == "whole" for k in range(4))


def test_a_second_ctrl_c_stops_after_the_files_being_written(tmp_path) -> None:
    code, stdout, files = _ctrl_c_while_writing(tmp_path, presses=2)
    assert code != 0 and stdout == ""
    assert {"file0", "file1"} <= files and not {"started2", "file2", "file3"} & files
    assert all((tmp_path / f"file{k}").read_text() == "whole" for k in (0, 1))
