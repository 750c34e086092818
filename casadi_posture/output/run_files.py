"""A simulated run's files in its folder: the tables (timeline.csv and .parquet, events.csv,
summary.json, manifest.json), the figures and report.html.

None of them reads another, so with more than one worker they are written side by side
by processes forked from this one, on Linux only: elsewhere forking a process that has
loaded numpy's BLAS and matplotlib is not safe (macOS) or not possible (Windows), and they
are written one after the other. The workers are forked after the run: they share it in
memory. A command forks, before its run, one process that imports matplotlib and the
drawing modules while the run goes on (``Writers``); it receives the run, without its
problem (it has it), and forks the workers. A 20-minute hold of the 29-DOF body has about
1.25 s of drawing and writing: 0.65 s on two cores, handed out the longest first."""

from __future__ import annotations

import contextlib
import ctypes
import functools
import gc
import itertools
import multiprocessing
import os
import pickle
import signal
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, replace
from multiprocessing.synchronize import Event as EventType
from pathlib import Path
from types import TracebackType
from typing import TypeVar

from casadi_posture import interrupt
from casadi_posture.errors import CasadiPostureError
from casadi_posture.output.low_back import step_low_back
from casadi_posture.output.movie_formats import WRITERS
from casadi_posture.output.results import write_results
from casadi_posture.output.scores import step_scores
from casadi_posture.problem import Problem
from casadi_posture.simulation import SimulationResult

T = TypeVar("T")

#: Most worker processes that write one run's files (it has at most 11 of them).
MOST_WORKERS = 4
#: Every file a run writes into its folder, figures and animation included: those of an
#: earlier run there (``--force``) are deleted first, so that none is left beside a new
#: run it does not belong to (a figure the new run does not draw, or is stopped before).
RUN_FILES = (
    "timeline.csv",
    "timeline.parquet",
    "events.csv",
    "summary.json",
    "manifest.json",
    "fatigue.png",
    "effector.png",
    "active_torque.png",
    "postures.png",
    "fatigue_regions.png",
    "schedule.png",
    "scores.png",
    "low_back.png",
    "report.html",
    *(f"animation.{name}" for name in WRITERS),
)
#: CPU time [s] of each file's job on the 20-minute hold of the 29-DOF body, measured by
#: benchmarks/command.py; an unlisted file counts 0.1 s. Handed out the longest first,
#: these jobs end on two cores 0.06 s sooner than in the files' order (0.67 s, not 0.73).
JOB_SECONDS = {
    "postures.png": 0.30,
    "scores.png": 0.20,
    "active_torque.png": 0.15,
    "low_back.png": 0.15,
    "tables": 0.12,
    "report.html": 0.14,
    "fatigue_regions.png": 0.11,
    "fatigue.png": 0.07,
    "effector.png": 0.07,
}


@dataclass(frozen=True)
class RunFiles:
    """The files written (tables, figures, report.html, in that order) and, when
    report.html was asked for but not written, why (the page is an extra: the run's
    other files are kept)."""

    paths: list[Path]
    report_missing: str | None = None


def cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux: no affinity to ask
        return os.cpu_count() or 1


def default_workers() -> int:
    """Worker processes for a run's files: the cores, at most ``MOST_WORKERS``."""
    return min(cores(), MOST_WORKERS)


def _forks() -> bool:
    return sys.platform.startswith("linux")


def write_run(
    result: SimulationResult,
    out: Path,
    *,
    command: list[str] | None = None,
    figures: bool = True,
    report: bool = True,
    workers: int = 1,
    writers: Writers | None = None,
    meanwhile: Callable[[], object] | None = None,
) -> RunFiles:
    """The run's tables, (with ``figures``) its figures and (with ``report``) report.html
    into ``out`` (an earlier run's files there deleted first: ``RUN_FILES``), by the
    ``writers`` forked before the run, else by ``workers`` processes forked now (1: in
    this one); ``command`` is recorded in the manifest. ``meanwhile`` runs in this process
    while they are written (before, when they are written here): a command prints its
    report."""
    out.mkdir(parents=True, exist_ok=True)
    for name in RUN_FILES:
        (out / name).unlink(missing_ok=True)
    spec = (out, command, figures, report)
    try:
        if writers is not None and writers.serve(result):
            done = writers.write(result, *spec, meanwhile=meanwhile)
        else:
            done = _written(result, spec, workers, meanwhile=meanwhile)
    except BrokenProcessPool:
        why = "ended abruptly (killed, or out of memory); the files it had written are kept"
        raise CasadiPostureError(f"a process writing the files into {out} {why}") from None
    paths = [p for d in done if not isinstance(d, str) for p in d]
    missing = done[-1] if report and isinstance(done[-1], str) else None
    return RunFiles(paths, missing)


def run_jobs(
    result: SimulationResult, out: Path, command: list[str] | None, figures: bool, report: bool
) -> dict[str, Callable[[], list[Path] | str]]:
    """Each file's job by the file's name ("tables" for the tables), in the order of
    ``RunFiles.paths``: the tables, each figure, the page (its paths, or why the page was
    not written)."""
    jobs: dict[str, Callable[[], list[Path] | str]] = {
        "tables": lambda: write_results(result, out, command=command)
    }
    if figures:
        from casadi_posture.output.plots import simulation_figures  # imported when drawn

        drawn = simulation_figures(result, out).items()
        jobs |= {name: lambda draw=draw: [draw()] for name, draw in drawn}
    if report:
        jobs["report.html"] = lambda: _page(result, out / "report.html")
    return jobs


def longest_first(names: Sequence[str]) -> list[int]:
    """The jobs' indices in the order they are handed out: by ``JOB_SECONDS``, longest
    first (the longest-processing-time rule: the last job to end is a short one)."""
    return sorted(range(len(names)), key=lambda k: -JOB_SECONDS.get(names[k], 0.1))


def _written(
    result: SimulationResult,
    spec: tuple[Path, list[str] | None, bool, bool],
    workers: int,
    stop: EventType | None = None,
    meanwhile: Callable[[], object] | None = None,
) -> list[list[Path] | str]:
    """``run_jobs``' values by ``workers`` processes forked here (``side_by_side``), the
    longest first; the scores and the low-back loads measured first, once, for all."""
    if workers > 1:
        step_scores(result)
        step_low_back(result)
    jobs = run_jobs(result, *spec)
    order = longest_first(list(jobs))
    return side_by_side(list(jobs.values()), workers, stop, meanwhile, order)


def _page(result: SimulationResult, path: Path) -> list[Path] | str:
    """report.html, or why it was not written."""
    from casadi_posture.output.html_report import write_report  # imported when drawn

    try:
        page = write_report(result, path)
    except KeyboardInterrupt:  # a second Ctrl-C while the page was written
        return "Ctrl-C"
    except Exception as error:  # the page is an extra: never lose the run over it
        return f"{type(error).__name__}: {error}"
    return [page] if page is not None else "no step was run"


class Writers:
    """A process forked now, before a run of ``problem``, that will write its files with
    ``workers`` processes it forks then (on Linux, more than one; else none, and the files
    are written one after the other here). It ignores Ctrl-C (this process decides) and,
    with ``draws``, imports the drawing modules while the run goes on. A context manager:
    leaving it lets the files being written finish and ends the process."""

    def __init__(self, workers: int, problem: Problem, *, draws: bool = True) -> None:
        self.problem = problem
        self.workers = workers if workers > 1 and _forks() else 1
        self._pool: ProcessPoolExecutor | None = None
        if self.workers > 1:
            global _PROBLEM, _STOP
            _PROBLEM, _STOP = problem, multiprocessing.get_context("fork").Event()
            self._stop = _STOP
            self._pool = _fork(1, functools.partial(_ready, draws))

    def __enter__(self) -> Writers:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """End the processes once the jobs they run are done."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def serve(self, result: SimulationResult) -> bool:
        """Whether these processes can write ``result``'s files: a run of their problem."""
        return self._pool is not None and result.problem is self.problem

    def write(
        self,
        result: SimulationResult,
        out: Path,
        command: list[str] | None,
        figures: bool,
        report: bool,
        *,
        meanwhile: Callable[[], object] | None = None,
    ) -> list[list[Path] | str]:
        """``run_jobs``' values: the run goes to the process pickled, without its problem
        (it was forked with it), with its scores and low-back loads measured here while
        the process still imports (``meanwhile`` needs them too), and its workers run the
        jobs while ``meanwhile`` runs here. A second Ctrl-C here lets the jobs being run
        finish and drops the others."""
        assert self._pool is not None and self.serve(result)
        measured = (replace(result, problem=None), step_scores(result), step_low_back(result))
        run = pickle.dumps(measured, pickle.HIGHEST_PROTOCOL)
        spec = (out, command, figures, report)
        written = self._pool.submit(_write_received, run, spec, self.workers)
        try:
            if meanwhile is not None:
                meanwhile()
            return written.result()
        except KeyboardInterrupt:
            self._stop.set()  # no further job handed out
            raise


def side_by_side(
    jobs: Sequence[Callable[[], T]],
    workers: int,
    stop: EventType | None = None,
    meanwhile: Callable[[], object] | None = None,
    order: Sequence[int] | None = None,
) -> list[T]:
    """Each job's value, in order; run by ``workers`` processes forked from this one now
    (they ignore Ctrl-C, which the terminal sends them too: this process decides), or here
    one after the other. A job's exception is raised here; a second Ctrl-C here lets the
    jobs being run finish (no half-written file) and drops the others, which are handed
    to a worker only when one is free (as they are once ``stop`` is set). ``meanwhile``
    runs here once the first jobs are handed out (first, when they are run here). The
    jobs are handed out in ``order`` (indices; by default, theirs)."""
    workers = min(workers, len(jobs))
    if workers <= 1 or not _forks():
        if meanwhile is not None:
            meanwhile()
        return [job() for job in jobs]
    global _JOBS
    _JOBS = jobs
    pool = _fork(workers, interrupt.ignore_in_worker)
    try:
        return _hand_out(pool, order or range(len(jobs)), workers, stop, meanwhile)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        _JOBS = ()


def _fork(workers: int, initializer: Callable[[], None]) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes forked now; their garbage collector leaves what
    they inherit alone. In a process that froze objects itself (the command's entry
    point), those made since stay frozen too: unfreezing would put the imports back into
    the collector's passes, the last of which, at exit, then took 0.06 s."""
    frozen = gc.get_freeze_count() > 0
    gc.freeze()
    try:
        starts = functools.partial(_worker_starts, os.getpid(), initializer)
        pool = ProcessPoolExecutor(workers, multiprocessing.get_context("fork"), starts)
        pool.submit(os.getpid)  # a forking pool forks all its workers on its first job
    finally:
        if not frozen:
            gc.unfreeze()
    return pool


def _hand_out(
    pool: ProcessPoolExecutor,
    order: Sequence[int],
    workers: int,
    stop: EventType | None,
    meanwhile: Callable[[], object] | None,
) -> list[T]:
    """The values of the inherited jobs in their own order, handed to a worker in
    ``order`` when one is free, ``workers`` at first; once ``stop`` is set, none more
    (``KeyboardInterrupt`` when the jobs being run are done); ``meanwhile`` run here once
    the first are handed out."""
    waiting = iter(order)
    running = {pool.submit(_inherited_job, k): k for k in itertools.islice(waiting, workers)}
    if meanwhile is not None:
        meanwhile()
    values: dict[int, T] = {}
    while running:
        done, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in done:
            values[running.pop(future)] = future.result()
            if stop is not None and stop.is_set():
                running.clear()
                raise KeyboardInterrupt
            running |= {pool.submit(_inherited_job, k): k for k in itertools.islice(waiting, 1)}
    return [values[k] for k in range(len(order))]


#: What the processes forked now inherit: the jobs (``side_by_side``); the problem of the
#: coming run and the request to stop handing out jobs (``Writers``).
_JOBS: Sequence[Callable[[], object]] = ()
_PROBLEM: Problem | None = None
_STOP: EventType | None = None


def _inherited_job(k: int) -> object:
    return _JOBS[k]()


def _write_received(run: bytes, spec: tuple, workers: int) -> list[list[Path] | str]:
    """In the ``Writers`` process: the run's files, by ``workers`` processes it forks."""
    if _NOT_READY is not None:
        raise _NOT_READY
    received, scores, back = pickle.loads(run)
    result = replace(received, problem=_PROBLEM)
    step_scores.remember(result, scores)
    step_low_back.remember(result, back)
    return _written(result, spec, workers, _STOP)


def _worker_starts(parent: int, ready: Callable[[], None]) -> None:
    """A forked worker ends with the process that forked it (Linux's parent-death
    signal): a worker left behind would wait for jobs forever, and its copy of the pipe
    that tells the parent's own parent that the parent ended would hide that end. Then
    ``ready``."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    if os.getppid() != parent:  # it ended before the signal was asked for
        os._exit(1)
    ready()


#: prctl's option that asks for a signal when the parent ends (linux/prctl.h).
PR_SET_PDEATHSIG = 1


def _ready(draws: bool) -> None:
    """The ``Writers`` process: Ctrl-C ignored; the Parquet writer (where the ``parquet``
    extra is installed) and, with ``draws``, the drawing modules imported (with the garbage
    collector off, then frozen, as the command's entry point does). An import that fails
    is kept (``_NOT_READY``) and raised when the run arrives: a pool whose initializer
    raises is only "broken", which would hide the real exception."""
    global _NOT_READY
    interrupt.ignore_in_worker()
    gc.disable()
    try:
        _import_writers(draws)
    except Exception as error:
        _NOT_READY = error
    gc.freeze()
    gc.enable()


def _import_writers(draws: bool) -> None:
    with contextlib.suppress(ImportError):  # no pyarrow: no timeline.parquet (write_results)
        import casadi_posture.output.arrow_columns
    if draws:
        import casadi_posture.output.html_report
        import casadi_posture.output.plots  # noqa: F401


#: Why the ``Writers`` process could not import what it writes with (``_ready``).
_NOT_READY: Exception | None = None
