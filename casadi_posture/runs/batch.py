"""Many cases at once: in parallel, on one machine or a Dask cluster, resumable.

A case is plain data (a problem file, dotted-key overrides, a solver); a worker
rebuilds every CasADi object from it and returns plain data (a summary row and
the bytes of its files), so nothing CasADi crosses a process boundary. The
calling process writes each case's folder atomically (a temporary folder renamed
into place), so a folder exists only complete: a killed batch rerun with
``resume`` redoes no finished case and finds no half-written one. The batch
summary is rebuilt from the case folders, sorted by case name and without wall
times, so it is the same whatever the number of jobs.

A case that ran records ``ok``, or ``flagged`` when its answer cannot be used as it is
(level 1 not reached, a group over strength, a solver that failed); one that could not
run records ``failed`` with a one-line reason (the traceback goes to its
``failure.json``); a problem without tasks is ``skipped``.
"""

from __future__ import annotations

import csv
import hashlib
import json
import multiprocessing
import os
import shutil
import sys
import tempfile
import time
import traceback
from collections.abc import Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

from tqdm import tqdm

from casadi_posture import __version__, interrupt
from casadi_posture.errors import MISSING, CasadiPostureError, ProblemError
from casadi_posture.frames import frame
from casadi_posture.ik.solvers import check_solver
from casadi_posture.output.plain import dumps, plain
from casadi_posture.output.rows import static_row
from casadi_posture.problem import Problem, load_problem, read_problem_text
from casadi_posture.static import rule, solve

CASES = "cases"
ROW = "row.json"
RUN = "run.json"
SUMMARY = "summary.csv"
LEADING = (
    "case",
    "status",
    "flags",
    "notes",
    "error",
    "problem",
    "solver",
    "strategy",
    "r_min",
    "recovery_law",
    "reached",
    "limiting_group_at_start",
    "limiting_endurance_at_start_min",
    "over_strength_at_start",
    "capable_male_pct",
    "capable_female_pct",
    "first_to_fatigue",
    "exhausted_group",
    "task_held_s",
    "task_held_is_lower_bound",
    "task_lost_reason",
)

#: A case's status: it ran and its answer stands (``ok``), it ran but its answer cannot be
#: used as it is (``flagged``: see its ``flags``), it could not run (``failed``: see its
#: ``error``), or there was nothing to run (``skipped``: a problem without tasks).
Status = Literal["ok", "flagged", "failed", "skipped"]

#: Longest one-line reason kept in a table or summary; the whole story is in failure.json.
REASON_CHARACTERS = 300


@dataclass(frozen=True)
class Case:
    """A problem file to run with ``overrides`` (dotted keys), ``solver`` (None: the
    file's), and either the full time simulation or only the static outcomes. ``text``
    carries the file's content to workers that have no copy of it (None: read the file
    where the case runs); ``report`` writes a simulated case's report.html; without
    ``files`` a case keeps only its summary row (no timeline, no figure: a population's
    workers)."""

    name: str
    problem: str
    overrides: dict[str, Any] = field(default_factory=dict)
    solver: str | None = None
    simulate: bool = True
    text: str | None = None
    report: bool = True
    files: bool = True

    def fingerprint(self) -> str:
        """A hash of everything that decides the case's result (and the tool's version)."""
        described = {k: v for k, v in asdict(self).items() if k != "text"}
        blob = json.dumps([__version__, described, self.text], sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()


@dataclass(frozen=True)
class Outcome:
    """What a worker returns: the case's summary row and its files' bytes."""

    name: str
    row: dict[str, Any]
    files: dict[str, bytes]


@dataclass(frozen=True)
class BatchReport:
    """The rows of every case in the output folder, sorted by case; how many cases ran now,
    how many were already done, and how many the run has; whether Ctrl-C stopped it (the
    finished cases are kept); the figures drawn from the rows (a what-if's outcomes)."""

    rows: list[dict[str, Any]]
    ran: int
    skipped: int
    summary: Path
    total: int
    interrupted: bool = False
    figures: tuple[Path, ...] = ()

    def with_status(self, *status: Status) -> list[dict[str, Any]]:
        return [r for r in self.rows if r["status"] in status]

    @property
    def failed(self) -> list[dict[str, Any]]:
        return self.with_status("failed")

    def to_frame(self) -> object:
        """One row per case as a pandas DataFrame (the columns of summary.csv)."""
        return frame([{k: plain(v) for k, v in row.items()} for row in self.rows])


def cases_from_paths(paths: Sequence[str | Path], solver: str | None = None) -> list[Case]:
    """One case per problem file; folders give their ``*.toml`` files. Named by file stem,
    or by the path where stems repeat."""
    check_solver(solver, paths[0] if paths else None, "--solver")
    files: list[Path] = []
    for item in map(Path, paths):
        if item.is_dir():
            files += sorted(item.glob("*.toml"))
        elif item.exists():
            files.append(item)
        else:
            raise ProblemError(item, None, None, "an existing problem file or folder")
    if not files:
        raise ProblemError(paths[0] if paths else None, None, None, "a folder with .toml files")
    stems = [f.stem for f in files]
    names = [
        f.stem if stems.count(f.stem) == 1 else safe_name(str(f.with_suffix(""))) for f in files
    ]
    return [
        Case(name, str(f), solver=solver, text=_text(f))
        for name, f in zip(names, files, strict=True)
    ]


def _text(path: Path) -> str | None:
    """The file's content, or None to let the case itself report why it cannot be read."""
    try:
        return read_problem_text(path)
    except ProblemError:
        return None


def run_case(case: Case) -> Outcome:
    """Run one case from its plain description (in any process); never raises but for
    Ctrl-C (``KeyboardInterrupt``: an interrupted case is not a finished one). A simulated
    case takes its start-posture outcomes from the simulation's first step, which solves
    the same IK from the same posture, so nothing is built twice."""
    row: dict[str, Any] = {"case": case.name, "problem": case.problem, **case.overrides}
    try:
        problem = load_problem(case.problem, case.overrides, text=case.text)
        row |= {
            "solver": case.solver or problem.spec.solver.name,
            "strategy": problem.spec.fatigue.strategy,
            "r_min": problem.spec.fatigue.r_min,
            "recovery_law": problem.fatigue.name,
            "endurance_rule": rule(problem),
            "notes": "; ".join(problem.notes),
        }
        if case.simulate and not problem.tasks:
            row |= {"status": "skipped", "flags": "", "error": "no tasks to hold"}
            return Outcome(case.name, row, {})
        files: dict[str, bytes] = {}
        if case.simulate:
            outcomes, files = _simulate(problem, case)
        else:
            outcomes = static_row(solve(problem, case.solver))
        flags = outcomes.pop("flags")
        status = "flagged" if flags else "ok"
        return Outcome(case.name, {**row, **outcomes, "status": status, "flags": flags}, files)
    except CasadiPostureError as error:
        reason, story = str(error), str(error)
    except Exception as error:  # a batch records any failure and carries on
        reason = one_line(f"{type(error).__name__}: {error}")
        story = traceback.format_exc()
    described = {k: v for k, v in asdict(case).items() if k != "text"}
    failure = dumps({"case": described, "error": reason, "traceback": story}).encode()
    row |= {"status": "failed", "flags": "", "error": reason}
    return Outcome(case.name, row, {"failure.json": failure})


def one_line(text: str) -> str:
    """The first line of ``text``, at most ``REASON_CHARACTERS`` long."""
    line = text.strip().splitlines()[0] if text.strip() else "unknown error"
    return line if len(line) <= REASON_CHARACTERS else line[: REASON_CHARACTERS - 3] + "..."


def _simulate(problem: Problem, case: Case) -> tuple[dict[str, Any], dict[str, bytes]]:
    """A simulated case's row and files (with ``report``, its report.html too: an extra,
    left out if it cannot be written; without ``files``, none)."""
    from casadi_posture.output.rows import simulation_row
    from casadi_posture.output.run_files import write_run
    from casadi_posture.simulation import simulate

    result = simulate(problem, case.solver)
    if result.stop == "interrupted":
        raise KeyboardInterrupt
    if not case.files:
        return simulation_row(result), {}
    with tempfile.TemporaryDirectory() as folder:
        written = write_run(result, Path(folder), report=case.report).paths  # the page: an extra
        files = {p.name: p.read_bytes() for p in written}
    return simulation_row(result), files


def run_batch(
    cases: Sequence[Case],
    out: Path,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    quiet: bool = False,
    describe: dict[str, Any] | None = None,
) -> BatchReport:
    """Run ``cases`` into ``out/cases/<name>/`` and write ``out/summary.csv`` (and
    ``summary.parquet`` when pyarrow is installed).

    ``out/run.json`` records the run (``describe``: what the user asked for, plus each
    case's fingerprint and the tool's version); ``resume`` continues only the same run,
    keeps its finished cases and runs again the failed ones. Ctrl-C stops the run within
    a second or two, keeps every finished case, cancels the rest and returns with
    ``interrupted``.
    """
    if jobs < 1:
        raise ProblemError(None, "jobs", jobs, "at least 1 worker process")
    names = [c.name for c in cases]
    if len(set(names)) != len(names):
        raise ProblemError(None, "cases", names, "unique case names")
    folder = out / CASES
    record = {
        "tool": {"name": "casadi_posture", "version": __version__},
        **(describe or {}),
        "cases": {c.name: c.fingerprint() for c in cases},
    }
    finished = _finished(folder)
    if finished and not resume:
        raise ProblemError(
            out, "--out", MISSING, "a folder without earlier results, or --resume to continue them"
        )
    if resume and finished:
        _same_run(out, record, finished)
    folder.mkdir(parents=True, exist_ok=True)
    (out / RUN).write_text(dumps(record) + "\n")
    for stale in folder.glob(".tmp-*"):
        shutil.rmtree(stale, ignore_errors=True)
    todo = [c for c in cases if finished.get(c.name) in (None, "failed")]
    bar = tqdm(
        total=len(todo), unit="case", file=sys.stderr, disable=quiet or not sys.stderr.isatty()
    )
    interrupted, ran = False, 0
    with interrupt.deferred():
        try:
            for outcome in _outcomes(todo, jobs, scheduler):
                _store(outcome, folder)
                ran += 1
                bar.update(1)
        except KeyboardInterrupt:
            interrupted = True
    bar.close()
    rows = sorted((_row(p) for p in folder.iterdir() if _is_case(p)), key=lambda r: r["case"])
    summary = write_summary(rows, out)
    return BatchReport(rows, ran, len(cases) - len(todo), summary, len(cases), interrupted)


def _is_case(path: Path) -> bool:
    """A finished case's folder (a folder a user added, or a rerun's, is not one)."""
    return path.is_dir() and not path.name.startswith(".") and (path / ROW).is_file()


def clear_run(out: Path, outputs: Sequence[str] = ()) -> None:
    """Delete an earlier run's files from ``out``: its cases, ``run.json``, its summary and
    the names or glob patterns in ``outputs``; nothing else of the folder."""
    shutil.rmtree(out / CASES, ignore_errors=True)
    for pattern in (RUN, SUMMARY, SUMMARY.replace(".csv", ".parquet"), *outputs):
        for path in out.glob(pattern):
            path.unlink()


def _row(path: Path) -> dict[str, Any]:
    return json.loads((path / ROW).read_text())


def _finished(folder: Path) -> dict[str, str]:
    """The status of every case folder already in ``folder``, by case name."""
    if not folder.exists():
        return {}
    return {p.name: _row(p)["status"] for p in folder.iterdir() if _is_case(p)}


def _same_run(out: Path, record: dict[str, Any], finished: dict[str, str]) -> None:
    """Refuse to resume a folder that holds another run: another tool version, other
    settings, other cases, or a finished case whose inputs changed (a failed case may
    change: it runs again)."""
    try:
        earlier = json.loads((out / RUN).read_text())
    except (OSError, ValueError):
        earlier = None
    if earlier is None:
        what = "no record of its run (run.json)"
    else:
        now = json.loads(dumps(record))
        settings = {k: v for k, v in now.items() if k != "cases"}
        same = settings == {k: v for k, v in earlier.items() if k != "cases"}
        same = same and set(earlier["cases"]) == set(now["cases"])
        changed = [
            name
            for name, status in finished.items()
            if status != "failed" and earlier["cases"].get(name) != now["cases"].get(name)
        ]
        if same and not changed:
            return
        what = (
            f"a run whose finished case {changed[0]} had other inputs"
            if same
            else "a different run (other problem files, varied keys or values, solver, "
            "static or simulated cases, tool version, or the case names of an earlier "
            "version: run it again)"
        )
    raise ProblemError(
        out,
        "--resume",
        MISSING,
        f"the same run as before, but the folder holds {what}; use a new --out",
    )


def _outcomes(todo: list[Case], jobs: int, scheduler: str | None) -> Iterator[Outcome]:
    """Outcomes as cases finish; raises ``KeyboardInterrupt`` on Ctrl-C, pending work
    cancelled and worker processes stopped."""
    if scheduler is not None:
        yield from _dask(todo, scheduler)
    elif jobs <= 1 or len(todo) <= 1:
        for case in todo:
            if interrupt.requested():
                raise KeyboardInterrupt
            yield run_case(case)
    else:
        yield from _processes(todo, jobs)


def _processes(todo: list[Case], jobs: int) -> Iterator[Outcome]:
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=jobs, mp_context=context, initializer=interrupt.ignore_in_worker
    )
    pending = {pool.submit(run_case, c) for c in todo}
    try:
        while pending:
            done, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
            for future in done:
                yield future.result()
            if interrupt.requested():
                raise KeyboardInterrupt
    finally:
        if pending:
            # Only the pool's own thread may cancel: a future cancelled here and then
            # failed by that thread when the workers die raises InvalidStateError there
            # (CPython 3.11), a traceback on the terminal after Ctrl-C.
            for process in multiprocessing.active_children():
                process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)


#: How often [s] a waiting batch looks for Ctrl-C.
POLL_S = 0.1
#: How long [s] to try to reach a Dask scheduler before saying it is not there.
CONNECT_S = 20.0


def _dask(todo: list[Case], scheduler: str) -> Iterator[Outcome]:
    try:
        from distributed import Client
    except ImportError:
        raise ProblemError(
            None, "--scheduler", scheduler, "Dask installed: pip install 'casadi_posture[dask]'"
        ) from None
    try:
        client = Client(scheduler, timeout=f"{CONNECT_S}s")
    except OSError as error:
        raise ProblemError(
            None, "--scheduler", scheduler, f"the address of a running Dask scheduler ({error})"
        ) from None
    with client:
        pending = set(client.map(run_case, todo, pure=False))
        try:
            while pending:
                done = {f for f in pending if f.done()}
                pending -= done
                for future in done:
                    yield future.result()
                if interrupt.requested():
                    raise KeyboardInterrupt
                if not done:
                    time.sleep(POLL_S)
        finally:
            if pending:
                client.cancel(list(pending))


def _store(outcome: Outcome, folder: Path) -> None:
    """Write a case's folder atomically: all its files, or nothing."""
    staging = Path(tempfile.mkdtemp(prefix=f".tmp-{outcome.name}-", dir=folder))
    for name, content in outcome.files.items():
        (staging / name).write_bytes(content)
    (staging / ROW).write_text(dumps(outcome.row) + "\n")
    target = folder / outcome.name
    if target.exists():
        shutil.rmtree(target)
    os.replace(staging, target)


def write_summary(rows: Sequence[dict[str, Any]], out: Path) -> Path:
    """``summary.csv`` (and ``.parquet`` when pyarrow is installed), written atomically.

    Empty cells (Parquet nulls) mean: unlimited for an endurance, never for a time, none
    for a group or a reason."""
    columns = list(LEADING) + sorted({k for r in rows for k in r} - set(LEADING))
    path = out / SUMMARY
    staging = path.with_suffix(".csv.tmp")
    with staging.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        writer.writerows({k: _cell(r.get(k)) for k in columns} for r in rows)
    os.replace(staging, path)
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return path
    table = pa.Table.from_pylist([{k: plain(r.get(k)) for k in columns} for r in rows])
    pq.write_table(table, str(path.with_suffix(".parquet.tmp")))
    os.replace(path.with_suffix(".parquet.tmp"), path.with_suffix(".parquet"))
    return path


def _cell(value: Any) -> Any:
    value = plain(value)
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return value


def safe_name(text: str) -> str:
    """A folder name: letters, digits and -_=.,+ kept, anything else as _."""
    return "".join(c if c.isalnum() or c in "-_=.,+" else "_" for c in text).strip("_")
