"""Many cases at once: in parallel, on one machine or a Dask cluster, resumable (SPEC §9).

A case is plain data (a problem file, dotted-key overrides, a solver); a worker
rebuilds every CasADi object from it and returns plain data (a summary row and
the bytes of its files), so nothing CasADi crosses a process boundary. The
calling process writes each case's folder atomically (a temporary folder renamed
into place), so a folder exists only complete: a killed batch rerun with
``resume`` redoes no finished case and finds no half-written one. The batch
summary is rebuilt from the case folders, sorted by case name and without wall
times, so it is the same whatever the number of jobs.
"""

from __future__ import annotations

import csv
import json
import math
import multiprocessing
import os
import shutil
import sys
import tempfile
import traceback
from collections.abc import Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from .endurance import endurance_model, half_joint_endurance_s
from .errors import CasadiPostureError, ProblemError
from .problem import Problem, load_problem, read_problem_text
from .solvers import make_solver

CASES = "cases"
ROW = "row.json"
LEADING = ("case", "status", "error", "problem", "solver", "strategy", "r_min")


@dataclass(frozen=True)
class Case:
    """A problem file to run with ``overrides`` (dotted keys), ``solver`` (None: the
    file's), and either the full time simulation or only the static outcomes. ``text``
    carries the file's content to workers that have no copy of it (None: read the file
    where the case runs)."""

    name: str
    problem: str
    overrides: dict[str, Any] = field(default_factory=dict)
    solver: str | None = None
    simulate: bool = True
    text: str | None = None


@dataclass(frozen=True)
class Outcome:
    """What a worker returns: the case's summary row and its files' bytes."""

    name: str
    ok: bool
    row: dict[str, Any]
    files: dict[str, bytes]


@dataclass(frozen=True)
class BatchReport:
    """The rows of every case in the output folder, sorted by case, and what ran now."""

    rows: list[dict[str, Any]]
    ran: int
    skipped: int
    summary: Path

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [r for r in self.rows if r["status"] != "ok"]


def cases_from_paths(paths: Sequence[str | Path], solver: str | None = None) -> list[Case]:
    """One case per problem file; folders give their ``*.toml`` files. Named by file stem,
    or by the path where stems repeat."""
    files: list[Path] = []
    for item in map(Path, paths):
        if item.is_dir():
            files += sorted(item.glob("*.toml"))
        elif item.exists():
            files.append(item)
        else:
            raise ProblemError(item, None, None, "an existing problem file or folder")
    if not files:
        raise ProblemError(None, "PROBLEM_OR_DIR", [str(p) for p in paths], "at least one .toml")
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
    """Run one case from its plain description (in any process); never raises. A simulated
    case takes its start-posture outcomes from the simulation's first step, which solves
    the same IK from the same posture, so nothing is built twice."""
    row: dict[str, Any] = {"case": case.name, "problem": case.problem, **case.overrides}
    try:
        problem = load_problem(case.problem, case.overrides, text=case.text)
        row |= {
            "solver": case.solver or problem.spec.solver.name,
            "strategy": problem.spec.fatigue.strategy,
            "r_min": problem.spec.fatigue.r_min,
        }
        files: dict[str, bytes] = {}
        if case.simulate:
            simulated, files = _simulate(problem, case.solver)
            row |= simulated
        else:
            row |= static_outcomes(problem, case.solver)
        return Outcome(case.name, True, {**row, "status": "ok", "error": ""}, files)
    except CasadiPostureError as error:
        reason = str(error)
    except Exception as error:  # a batch records any failure and carries on
        reason = f"{type(error).__name__}: {error} ({traceback.format_exc(limit=-1).strip()})"
    described = {k: v for k, v in asdict(case).items() if k != "text"}
    failure = json.dumps({"case": described, "error": reason}, indent=2).encode()
    return Outcome(
        case.name, False, {**row, "status": "failed", "error": reason}, {"failure.json": failure}
    )


def static_outcomes(problem: Problem, solver: str | None) -> dict[str, Any]:
    """Outcomes from torques alone at the solved start posture: each half-joint's load and
    maximum holding time, and the limiting group (the shortest one)."""
    q = problem.posture
    if problem.tasks:
        name = solver or problem.spec.solver.name
        q = make_solver(name, problem.hierarchy(), problem.spec.solver).solve(q).q
    loads = problem.torque_model().evaluate(q).load_pct_mvc
    model = endurance_model(problem.spec.fatigue.endurance)
    return _endurance_columns(
        {
            half.name: (
                float(loads[k]),
                half_joint_endurance_s(model, float(loads[k]), half.region),
            )
            for k, half in enumerate(problem.body.half_joints)
        }
    )


def _endurance_columns(groups: dict[str, tuple[float, float]]) -> dict[str, Any]:
    """Columns of each half-joint's start load [%MVC] and endurance [min] (from seconds),
    and the limiting group: the one with the shortest endurance."""
    row: dict[str, Any] = {}
    for name, (load, seconds) in groups.items():
        row[f"initial_load_{name}_pct_mvc"] = load
        row[f"initial_endurance_{name}_min"] = seconds / 60
    limiting = min(groups, key=lambda name: groups[name][1])
    return row | {"limiting_group": limiting, "limiting_endurance_min": groups[limiting][1] / 60}


def _simulate(problem: Problem, solver: str | None) -> tuple[dict[str, Any], dict[str, bytes]]:
    from .plots import plot_simulation
    from .results import summary, write_results
    from .simulation import simulate

    result = simulate(problem, solver)
    report = summary(result)
    with tempfile.TemporaryDirectory() as folder:
        written = write_results(result, Path(folder)) + plot_simulation(result, Path(folder))
        files = {p.name: p.read_bytes() for p in written}
    lost = report["task_lost"]
    first = report["first_to_fatigue"]
    start = {
        g["half_joint"]: (
            g["initial_load_pct_mvc"],
            math.inf if g["initial_endurance_min"] is None else 60 * g["initial_endurance_min"],
        )
        for g in report["half_joints"]
    }
    row: dict[str, Any] = _endurance_columns(start) | {
        "simulated_s": report["simulated_s"],
        "first_to_fatigue": first["half_joint"] if first else "",
        "first_fatigue_s": first["time_s"] if first else None,
        "fatigue_recovery_cycles": report["fatigue_recovery_cycles"],
        "task_lost": lost is not None,
        "task_held_s": lost["time_s"] if lost else report["simulated_s"],
        "ik_failures": report["solver_statistics"]["ik_failures"],
    }
    for group in report["half_joints"]:
        row[f"fatigue_threshold_{group['half_joint']}_s"] = group["first_fatigue_threshold_s"]
    recoveries = report["recovery_postures"]
    for dof in problem.body.dof_names:
        row[f"recovery_{dof}_deg"] = recoveries[0]["posture_deg"][dof] if recoveries else None
    return row, files


def run_batch(
    cases: Sequence[Case],
    out: Path,
    *,
    jobs: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    quiet: bool = False,
) -> BatchReport:
    """Run ``cases`` into ``out/cases/<name>/`` and write ``out/summary.csv`` (and
    ``summary.parquet`` when pyarrow is installed)."""
    names = [c.name for c in cases]
    if len(set(names)) != len(names):
        raise ProblemError(None, "cases", names, "unique case names")
    folder = out / CASES
    done = (
        {p.name for p in folder.iterdir() if p.is_dir() and not p.name.startswith(".")}
        if folder.exists()
        else set()
    )
    if done and not resume:
        raise ProblemError(
            None,
            "--out",
            str(out),
            "a folder without earlier results, or --resume to continue them",
        )
    folder.mkdir(parents=True, exist_ok=True)
    for stale in folder.glob(".tmp-*"):
        shutil.rmtree(stale, ignore_errors=True)
    todo = [c for c in cases if c.name not in done]
    bar = tqdm(
        total=len(todo), unit="case", file=sys.stderr, disable=quiet or not sys.stderr.isatty()
    )
    for outcome in _outcomes(todo, jobs, scheduler):
        _store(outcome, folder)
        bar.update(1)
    bar.close()
    rows = sorted(
        (
            json.loads((p / ROW).read_text())
            for p in folder.iterdir()
            if p.is_dir() and not p.name.startswith(".")
        ),
        key=lambda r: r["case"],
    )
    summary = write_summary(rows, out)
    return BatchReport(rows, len(todo), len(cases) - len(todo), summary)


def _outcomes(todo: list[Case], jobs: int, scheduler: str | None) -> Iterator[Outcome]:
    if scheduler is not None:
        yield from _dask(todo, scheduler)
    elif jobs <= 1 or len(todo) <= 1:
        yield from map(run_case, todo)
    else:
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
            for future in as_completed([pool.submit(run_case, c) for c in todo]):
                yield future.result()


def _dask(todo: list[Case], scheduler: str) -> Iterator[Outcome]:
    try:
        from distributed import Client
        from distributed import as_completed as completed
    except ImportError:
        raise ProblemError(
            None, "--scheduler", scheduler, "Dask installed: pip install 'casadi_posture[dask]'"
        ) from None
    try:
        client = Client(scheduler, timeout="20s")
    except OSError as error:
        raise ProblemError(
            None, "--scheduler", scheduler, f"the address of a running Dask scheduler ({error})"
        ) from None
    with client:
        futures = client.map(run_case, todo, pure=False)
        for future in completed(futures):
            yield future.result()


def _store(outcome: Outcome, folder: Path) -> None:
    """Write a case's folder atomically: all its files, or nothing."""
    staging = Path(tempfile.mkdtemp(prefix=f".tmp-{outcome.name}-", dir=folder))
    for name, content in outcome.files.items():
        (staging / name).write_bytes(content)
    (staging / ROW).write_text(json.dumps(_plain(outcome.row), indent=2, allow_nan=False) + "\n")
    target = folder / outcome.name
    if target.exists():
        shutil.rmtree(target)
    os.replace(staging, target)


def write_summary(rows: Sequence[dict[str, Any]], out: Path) -> Path:
    """``summary.csv`` (and ``.parquet`` when pyarrow is installed), written atomically."""
    columns = list(LEADING) + sorted({k for r in rows for k in r} - set(LEADING))
    path = out / "summary.csv"
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
    table = pa.Table.from_pylist([{k: r.get(k) for k in columns} for r in rows])
    pq.write_table(table, str(path.with_suffix(".parquet.tmp")))
    os.replace(path.with_suffix(".parquet.tmp"), path.with_suffix(".parquet"))
    return path


def _plain(row: dict[str, Any]) -> dict[str, Any]:
    """JSON-able row: infinities as None, numpy scalars as Python numbers."""
    out = {}
    for key, value in row.items():
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, float) and not math.isfinite(value):
            value = None
        out[key] = value
    return out


def _cell(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    return value


def safe_name(text: str) -> str:
    """A folder name: letters, digits and -_=., kept, anything else as _."""
    return "".join(c if c.isalnum() or c in "-_=.," else "_" for c in text).strip("_")
