"""A simulated run's files in its folder: the tables (timeline.csv and .parquet, events.csv,
summary.json, manifest.json), the figures and report.html.

None of them reads another, so with ``workers`` > 1 they are written side by side by
worker processes forked from this one, which share the run in memory and need not import
anything again. A 20-minute hold of the 29-DOF body has about 2 s of drawing and writing:
about 1 s on two cores. Only on Linux: elsewhere forking a process that has loaded
numpy's BLAS and matplotlib is not safe (macOS) or not possible (Windows), and they are
written one after the other."""

from __future__ import annotations

import functools
import gc
import itertools
import multiprocessing
import os
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from casadi_posture import interrupt
from casadi_posture.output.html_report import write_report
from casadi_posture.output.low_back import step_low_back
from casadi_posture.output.plots import simulation_figures
from casadi_posture.output.results import write_results
from casadi_posture.output.scores import step_scores
from casadi_posture.simulation import SimulationResult

T = TypeVar("T")

#: Most worker processes that write one run's files (it has at most 11 of them).
MOST_WORKERS = 4


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


def write_run(
    result: SimulationResult,
    out: Path,
    *,
    command: list[str] | None = None,
    figures: bool = True,
    report: bool = True,
    workers: int = 1,
) -> RunFiles:
    """The run's tables, (with ``figures``) its figures and (with ``report``) report.html
    into ``out``, by ``workers`` processes side by side (1: in this one); ``command`` is
    recorded in the manifest."""
    out.mkdir(parents=True, exist_ok=True)
    step_scores(result)  # measured once here, shared by the forked workers
    step_low_back(result)
    tables = functools.partial(write_results, result, out, command=command)
    jobs: list[Callable[[], list[Path] | str]] = [tables]
    if figures:
        jobs += [lambda draw=draw: [draw()] for draw in simulation_figures(result, out)]
    if report:
        jobs.append(lambda: _page(result, out / "report.html"))
    done = side_by_side(jobs, workers)
    paths = [p for d in done if not isinstance(d, str) for p in d]
    missing = done[-1] if report and isinstance(done[-1], str) else None
    return RunFiles(paths, missing)


def _page(result: SimulationResult, path: Path) -> list[Path] | str:
    """report.html, or why it was not written."""
    try:
        page = write_report(result, path)
    except KeyboardInterrupt:  # a second Ctrl-C while the page was written
        return "Ctrl-C"
    except Exception as error:  # the page is an extra: never lose the run over it
        return f"{type(error).__name__}: {error}"
    return [page] if page is not None else "no step was run"


#: The jobs the forked workers run, by index (set before they are forked: they inherit it).
_JOBS: Sequence[Callable[[], object]] = ()


def _job(index: int) -> object:
    return _JOBS[index]()


def side_by_side(jobs: Sequence[Callable[[], T]], workers: int) -> list[T]:
    """Each job's value, in order; run by ``workers`` processes forked from this one (they
    ignore Ctrl-C, which the terminal sends them too: this process decides), or here one
    after the other. A job's exception is raised here; a second Ctrl-C here lets the jobs
    being run finish (no half-written file) and drops the others, which are handed to a
    worker only when one is free."""
    workers = min(workers, len(jobs))
    if workers <= 1 or not sys.platform.startswith("linux"):
        return [job() for job in jobs]
    global _JOBS
    _JOBS = jobs
    gc.freeze()  # the workers' garbage collector leaves what they inherit alone
    context = multiprocessing.get_context("fork")
    pool = ProcessPoolExecutor(workers, context, initializer=interrupt.ignore_in_worker)
    try:
        waiting = iter(range(len(jobs)))
        running = {pool.submit(_job, k): k for k in itertools.islice(waiting, workers)}
        values: dict[int, T] = {}
        while running:  # a job handed out when a worker is free: none queued to cancel
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                values[running.pop(future)] = future.result()
                running |= {pool.submit(_job, k): k for k in itertools.islice(waiting, 1)}
        return [values[k] for k in range(len(jobs))]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        gc.unfreeze()
        _JOBS = ()
