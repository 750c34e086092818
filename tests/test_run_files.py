"""A run's files written side by side by processes forked from this one, after the run or
(``Writers``) before it: the same bytes as one after the other, a job's error raised here,
Ctrl-C leaving no file half written; the modules a command loads before its run draw
nothing."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest
from conftest import PROBLEMS

from casadi_posture import api
from casadi_posture.output.per_run import once_per_run
from casadi_posture.output.run_files import (
    RUN_FILES,
    Writers,
    longest_first,
    side_by_side,
    write_run,
)

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
    assert set(names) <= set(RUN_FILES)  # a later run written over it deletes every one


def test_an_earlier_run_s_files_are_not_left_beside_a_new_one(tmp_path) -> None:
    """Written over (``--force``), a folder keeps no file of the earlier run (here the
    low back of a 3-D body, a schedule, an animation, a page) that the new one does not
    write again (a planar run without its page), and keeps the user's own."""
    earlier = ["schedule.png", "low_back.png", "animation.gif", "report.html"]
    for name in [*earlier, "fatigue.png", "notes.txt"]:
        (tmp_path / name).write_text("earlier")
    run = api.simulate(api.load(PROBLEMS / "holding_m45.toml", {"simulation.duration_s": 5.0}))
    files = write_run(run.result, tmp_path, report=False)
    assert not any((tmp_path / name).exists() for name in earlier)
    assert (tmp_path / "notes.txt").read_text() == "earlier"
    assert (tmp_path / "fatigue.png").read_bytes().startswith(b"\x89PNG")  # the new one
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted([*(p.name for p in files.paths), "notes.txt"])
    assert {p.name for p in files.paths} <= set(RUN_FILES)


def test_writers_forked_before_the_run_write_the_same_files(standing, tmp_path) -> None:
    """The process forked with the problem receives the run without it and writes the same
    bytes; a run of another problem is written here instead."""
    one = write_run(standing.result, tmp_path / "one", command=["x"], workers=1)
    with Writers(2, standing.result.problem) as writers:
        assert writers.serve(standing.result) and writers.workers == 2
        two = write_run(standing.result, tmp_path / "two", command=["x"], writers=writers)
        other = api.load(PROBLEMS / "holding_m45.toml", {"simulation.duration_s": 5.0})
        assert not writers.serve(api.simulate(other).result)
    assert [p.name for p in one.paths] == [p.name for p in two.paths]
    for a, b in zip(one.paths, two.paths, strict=True):
        if a.name != "manifest.json":
            assert a.read_bytes() == b.read_bytes(), a.name
    assert Writers(1, standing.result.problem).workers == 1  # nothing forked: written here


def test_a_measure_sent_with_the_run_is_not_measured_again(standing) -> None:
    """The ``Writers`` process keeps the scores measured by the command (``remember``)."""
    calls = []
    measure = once_per_run(lambda result: calls.append(result) or len(calls))
    assert measure(standing.result) == 1 and measure(standing.result) == 1
    other = replace(standing.result)
    assert measure.remember(other, 7) == 7 and measure(other) == 7 and len(calls) == 1
    assert measure(standing.result) == 2  # only the last run is kept


def test_the_commands_modules_load_no_drawing_module_before_the_run(tmp_path) -> None:
    """What lets ``Writers`` import matplotlib while the run goes on; and the library
    never chooses a backend for the user's own plots (it draws on Figure objects)."""
    script = (
        "import sys\n"
        "import casadi_posture as cp, casadi_posture.cli\n"
        "print(sorted(m for m in ('matplotlib', 'pyarrow', 'pandas') if m in sys.modules))\n"
        "import matplotlib\n"
        "matplotlib.use('svg')\n"
        f"problem = cp.load({str(PROBLEMS / 'holding_m45.toml')!r})\n"
        "cp.plot_curve(cp.curve(problem, problem.body.dof_names[0]), sys.argv[1])\n"
        "print(matplotlib.get_backend())\n"
    )
    shown = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path / "curve.png")],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split("\n")
    assert shown[:2] == ["[]", "svg"]


def test_once_stop_is_set_no_further_job_is_handed_out(tmp_path) -> None:
    """``Writers``' second Ctrl-C: the process writing the files hears it through ``stop``;
    the jobs being run finish, the others are dropped."""
    stop = multiprocessing.get_context("fork").Event()

    def job(k: int):
        def write() -> int:
            if k == 1:
                stop.set()
            time.sleep(0.3)
            (tmp_path / f"file{k}").write_text("whole")
            return k

        return write

    with pytest.raises(KeyboardInterrupt):
        side_by_side([job(k) for k in range(5)], 2, stop)
    assert {p.name for p in tmp_path.iterdir()} == {"file0", "file1"}


def test_a_job_s_error_is_raised_here(tmp_path) -> None:
    def fails() -> None:
        raise ZeroDivisionError("in a worker")

    jobs = [lambda: (tmp_path / "a").write_text("a"), fails, lambda: 3]
    with pytest.raises(ZeroDivisionError, match="in a worker"):
        side_by_side(jobs, 2)
    assert side_by_side([lambda: 1, lambda: os.getpid()], 2)[1] != os.getpid()  # forked
    assert side_by_side([lambda: 1, lambda: os.getpid()], 1) == [1, os.getpid()]  # here


def test_jobs_are_handed_out_in_the_order_asked_and_answered_in_their_own(tmp_path) -> None:
    def job(k: int):
        def started() -> int:
            (tmp_path / f"start{k}").write_text(str(time.monotonic()))
            time.sleep(0.2)
            return k

        return started

    assert side_by_side([job(k) for k in range(4)], 2, order=[3, 2, 1, 0]) == [0, 1, 2, 3]
    start = {k: float((tmp_path / f"start{k}").read_text()) for k in range(4)}
    assert max(start[3], start[2]) < min(start[1], start[0])


def test_the_longest_files_are_written_first() -> None:
    names = ["tables", "fatigue.png", "effector.png", "postures.png", "scores.png", "x.png"]
    order = [names[k] for k in longest_first(names)]
    assert order[0] == "postures.png" and order[1] == "scores.png"
    assert order[-2:] == ["fatigue.png", "effector.png"] and sorted(order) == sorted(names)


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


def test_a_run_stopped_before_its_first_step_is_said_and_exits_130(monkeypatch, capsys) -> None:
    """Ctrl-C while the run was being built: no step, no table of loads to print."""
    from casadi_posture import interrupt
    from casadi_posture.cli.runs import _report

    monkeypatch.setattr(interrupt, "requested", lambda: True)
    run = api.simulate(api.load(PROBLEMS / "holding_m45.toml"))
    assert run.result.timeline.time.size == 0 and run.stop == "interrupted"
    assert _report(run, "law") == interrupt.EXIT_CODE
    assert "no step was run (interrupted)" in capsys.readouterr().out


#: Writers whose jobs leave their process id and sleep; the process writing is killed once
#: they have started: the command says so in one error, and no process is left behind.
KILLED = """
import os, sys, time
from pathlib import Path
from casadi_posture import api
from casadi_posture.errors import CasadiPostureError
from casadi_posture.output import run_files

out = Path(sys.argv[1])

def sleeping(result, folder, command, figures, report):
    def job():
        (out / f"worker{os.getpid()}").touch()
        time.sleep(60)
    return {"one": job, "two": job}

run_files.run_jobs = sleeping
problem = api.load(sys.argv[2], {"simulation.duration_s": 5.0})
with run_files.Writers(2, problem) as writers:
    (out / f"writer{next(iter(writers._pool._processes))}").touch()
    run = api.simulate(problem)
    try:
        run_files.write_run(run.result, out / "files", writers=writers)
    except CasadiPostureError as error:
        print(error, flush=True)
"""


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0]
    except FileNotFoundError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux")
def test_a_killed_writing_process_is_an_error_and_leaves_no_process(tmp_path) -> None:
    process = subprocess.Popen(
        [sys.executable, "-c", KILLED, str(tmp_path), str(PROBLEMS / "holding_m45.toml")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while len(list(tmp_path.glob("worker*"))) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    workers = [int(p.name.removeprefix("worker")) for p in tmp_path.glob("worker*")]
    (writer,) = [int(p.name.removeprefix("writer")) for p in tmp_path.glob("writer*")]
    assert len(workers) == 2 and all(_running(pid) for pid in workers)
    os.kill(writer, signal.SIGKILL)
    stdout, _ = process.communicate(timeout=30)  # it used to wait for ever
    assert "ended abruptly (killed, or out of memory)" in stdout
    time.sleep(0.5)
    assert not any(_running(pid) for pid in workers)  # they end with the writer
