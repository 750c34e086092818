"""A population run (``casadi-posture population``; docs/population.md): every virtual
worker of ``population.sampling`` holding the problem's task on a body of their own, run as
batch cases, and the share of each sex still holding it over time."""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from casadi_posture.biomech.capability import PEOPLE, SEXES, Sex
from casadi_posture.data.parameters import data_name
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.people.sampling import Worker, draw_workers, group_correlation
from casadi_posture.people.statistics import wilson
from casadi_posture.problem import Problem
from casadi_posture.runs.batch import BatchReport, Case

#: The body's keys every worker has its own of: an override of one would be lost.
DRAWN_KEYS = frozenset({"body.sex", "body.stature_m", "body.mass_kg", "body.age_years"})
#: How long [min] the summary asks who still holds the task.
HORIZONS_MIN = (1, 2, 5, 10, 20)
#: The strength keys a problem file may set on a group, and whether a factor scales them.
SCALED_KEYS = ("strength_scale", "strength_Nm", "strength_ratio")


@dataclass(frozen=True)
class Share:
    """The share of ``n`` workers still holding at ``minutes`` (``held``): a proportion and
    its Wilson 95 % interval; None where the run stopped before (``beyond_run``)."""

    minutes: float
    n: int
    held: int | None
    share: float | None
    low: float | None
    high: float | None


def worker_cases(
    problem: Problem, text: str, workers: Sequence[Worker], solver: str | None, files: bool
) -> tuple[list[Case], list[str]]:
    """One batch case per worker: the problem (``text``, the file's content) with the
    worker's sex, stature, mass and age and each group's strength times the worker's factor;
    also the groups not varied (a strength curve the file sets). A problem without a
    built-in body model is refused."""
    body = problem.spec.body
    if body.model is None:
        expected = "a built-in body.model: a tree of your own has no sex and stature to draw"
        raise ProblemError(problem.path, "body.tree", MISSING, expected)
    cases, fixed = [], []
    own = body.half_joints
    for worker in workers:
        overrides: dict[str, Any] = {
            "body.sex": worker.sex,
            "body.stature_m": round(worker.stature_m, 4),
            "body.mass_kg": round(worker.mass_kg, 2),
            "body.age_years": round(worker.age_years, 2),
        }
        for half in problem.body.half_joints:
            factor = worker.strength[data_name(half.name)]
            spec = own.get(half.name)
            given = {k: getattr(spec, k) for k in SCALED_KEYS if spec and getattr(spec, k)}
            if spec is not None and spec.strength_curve is not None:
                fixed.append(half.name)
                continue
            key, value = next(iter(given.items()), ("strength_scale", 1.0))
            overrides[f"body.half_joints.{half.name}.{key}"] = round(value * factor, 6)
        cases.append(
            Case(
                worker.name,
                str(problem.path),
                overrides,
                solver,
                text=text,
                report=files,
                files=files,
            )
        )
    return cases, sorted(set(fixed))


def draw(problem: Problem, n: int, sexes: Sequence[Sex], seed: int, **kwargs: Any) -> list[Worker]:
    """The workers of a population run on ``problem``: ``n`` of each of ``sexes``, with a
    strength factor per muscle group of its body (``draw_workers``)."""
    groups = sorted({data_name(h.name) for h in problem.body.half_joints})
    return draw_workers(n, sexes, groups, seed, **kwargs)


def shares(
    rows: Sequence[Mapping[str, Any]], horizons: Sequence[float] = HORIZONS_MIN
) -> list[Share]:
    """Of the workers that ran (``rows`` of one sex, failed ones left out), the share still
    holding the task at each horizon [min]: held at least that long (a run that ended with
    the task held counts for every horizon up to its end)."""
    ran = [r for r in rows if r.get("status") in ("ok", "flagged")]
    out = []
    for minutes in horizons:
        seconds = 60.0 * minutes
        beyond = any(
            float(r["simulated_s"]) < seconds - 1e-9 and r["task_held_is_lower_bound"] for r in ran
        )
        if not ran or beyond:
            out.append(Share(minutes, len(ran), None, None, None, None))
            continue
        held = sum(float(r["task_held_s"]) >= seconds - 1e-9 for r in ran)
        low, high = wilson(held, len(ran))
        out.append(Share(minutes, len(ran), held, held / len(ran), low, high))
    return out


def sustainable(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Of the workers that ran (``rows`` of one sex), how many held the task, with its
    schedule if it has one, for the whole run without any group reaching the fatigue
    threshold (the constraint never engaged): ``duty-cycle``'s "sustainable", per
    person; a proportion and its Wilson 95 % interval (None: nobody ran)."""
    ran = [r for r in rows if r.get("status") in ("ok", "flagged")]
    count = sum(r.get("stop") == "completed" and r.get("first_fatigue_s") is None for r in ran)
    low, high = wilson(count, len(ran)) if ran else (None, None)
    return {
        "n": len(ran),
        "count": count,
        "share": count / len(ran) if ran else None,
        "low": low,
        "high": high,
    }


def population_summary(
    report: BatchReport, workers: Sequence[Worker], fixed: Sequence[str]
) -> dict[str, Any]:
    """What population.json holds: per sex the workers drawn, run, failed and flagged (an
    answer that needs care, over strength at the start say: their rows say why), the shares
    still holding at ``HORIZONS_MIN`` with their intervals, the share for whom the task (on
    its schedule) is sustainable over the whole run, the median time held [s], the regions
    that gave out first and the limiting regions at the start, counted; the groups not
    varied; the workers' notes (``worker_notes``)."""
    by_name = {w.name: w for w in workers}
    notes = worker_notes([r for r in report.rows if r["case"] in by_name])
    out: dict[str, Any] = {"groups_not_varied": list(fixed), "notes": notes, "sexes": {}}
    for sex in SEXES:
        rows = [r for r in report.rows if r["case"] in by_name and by_name[r["case"]].sex == sex]
        if not rows:
            continue
        ran = [r for r in rows if r.get("status") in ("ok", "flagged")]
        held = sorted(float(r["task_held_s"]) for r in ran)
        out["sexes"][sex] = {
            "people": PEOPLE[sex],
            "drawn": len(rows),
            "ran": len(ran),
            "failed": len(rows) - len(ran),
            "flagged": sum(r.get("status") == "flagged" for r in rows),
            "still_holding": [s.__dict__ for s in shares(rows)],
            "sustainable": sustainable(rows),
            "median_task_held_s": held[len(held) // 2] if held else None,
            "exhausted_region": dict(Counter(r["exhausted_region"] or "none" for r in ran)),
            "limiting_region_at_start": dict(
                Counter(r.get("limiting_region_at_start") or "none" for r in ran)
            ),
        }
    return out


def worker_notes(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The distinct notes of the workers' problems (spec/slips.py: a load in grams is every
    worker's, a body mass index out of range one worker's), each once, in the order met,
    prefixed with how many workers it concerns unless it concerns all of them."""
    counts = Counter(r["notes"] for r in rows if r.get("notes"))
    return [
        note if count == len(rows) else f"{count} of {len(rows)} workers: {note}"
        for note, count in counts.items()
    ]


def check_size(n: int, sexes: Sequence[str], max_cases: int, problem: Path | None) -> None:
    """``n`` workers per sex of ``sexes``: at least 1, and at most ``max_cases`` cases in
    all; else a one-line error."""
    if n < 1:
        raise ProblemError(problem, "--n", n, "at least 1 worker per sex")
    if n * len(sexes) > max_cases:
        expected = f"at most {max_cases} workers in all (--max-cases raises it)"
        raise ProblemError(problem, "--n", n, expected)


#: Workers in all a run takes without ``max_cases`` raised.
MAX_WORKERS = 2000
#: What a population run writes beside the batch's cases/, summary.csv and run.json.
POPULATION_OUTPUTS = ("population.json", "survival.png", "held_vs_stature.png")


@dataclass(frozen=True)
class PopulationReport:
    """A population run: the batch of its workers, population.json's content and the
    figures."""

    batch: BatchReport
    summary: dict[str, Any]
    figures: tuple[Path, ...]


def run_population(
    problem: Problem,
    text: str,
    out: Path,
    *,
    n: int,
    sexes: Sequence[Sex],
    seed: int,
    correlation: float | None,
    solver: str | None,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    files: bool,
    max_cases: int,
    quiet: bool,
) -> PopulationReport:
    """Draw the workers, run each as a batch case into ``out`` (resumable, on ``jobs``
    local processes or a Dask ``scheduler``) and write population.json and the figures."""
    from casadi_posture.output.plain import dumps
    from casadi_posture.output.population_plots import plot_held_vs_stature, plot_survival
    from casadi_posture.runs.batch import run_batch

    if not problem.tasks:
        expected = "at least one task for the workers to hold"
        raise ProblemError(problem.path, "tasks", MISSING, expected)
    check_size(n, sexes, max_cases, problem.path)
    for key in DRAWN_KEYS & problem.overrides.keys():
        expected = "not set: each worker's own is drawn (--sex chooses the sexes)"
        raise ProblemError(problem.path, key, problem.overrides[key], expected)
    try:
        workers = draw(problem, n, sexes, seed, correlation=correlation)
    except ValueError as error:
        raise ProblemError(None, "--correlation", correlation, "0 to 1") from error
    cases, fixed = worker_cases(problem, text, workers, solver, files)
    given = dict(problem.overrides)
    cases = [replace(c, overrides={**given, **c.overrides}) for c in cases]
    rho = correlation if correlation is not None else group_correlation()
    described = {
        "kind": "population",
        "problem": str(problem.path),
        "n_per_sex": n,
        "sexes": list(sexes),
        "seed": seed,
        "group_correlation": rho,
        "solver": solver,
        "overrides": given,
        "horizon_s": problem.spec.simulation.duration_s,
        "schedule": None if problem.spec.schedule is None else problem.spec.schedule.model_dump(),
    }
    batch = run_batch(
        cases, out, jobs=jobs, scheduler=scheduler, resume=resume, quiet=quiet, describe=described
    )
    finished = {
        "workers_finished": len(batch.rows),
        "workers_total": batch.total,
        "interrupted": batch.interrupted,  # the shares are those of the finished workers
    }
    summary = {**described, **finished, **population_summary(batch, workers, fixed)}
    (out / "population.json").write_text(dumps(summary) + "\n")
    title = f"{problem.path.stem}: {n} workers per sex, seed {seed}"
    figures: tuple[Path, ...] = ()
    if any(r.get("status") in ("ok", "flagged") for r in batch.rows):
        figures = (
            plot_survival(batch.rows, out / "survival.png", title),
            plot_held_vs_stature(batch.rows, out / "held_vs_stature.png", title),
        )
    return PopulationReport(batch, summary, figures)
