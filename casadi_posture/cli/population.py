"""``casadi-posture population``: virtual workers holding a task (docs/population.md)."""

from __future__ import annotations

from pathlib import Path

import click

from casadi_posture import api
from casadi_posture.cli.common import (
    INTERRUPTED,
    SET_OPTION,
    SOLVER_OPTION,
    batch_options,
    main,
    out_option,
    parse_sets,
)
from casadi_posture.output.report import table
from casadi_posture.runs.population import MAX_WORKERS

SEXES = {"male": ("male",), "female": ("female",), "both": ("male", "female")}


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("--n", "n", type=int, required=True, help="Workers of each sex.")
@click.option(
    "--sex",
    type=click.Choice(list(SEXES)),
    default="both",
    show_default=True,
    help="The sexes drawn.",
)
@click.option("--seed", type=int, default=1, show_default=True, help="The draw's seed.")
@click.option(
    "--correlation",
    type=float,
    default=None,
    help="Correlation of one worker's strengths in two muscle groups, 0 to 1 [default: "
    "0.3, docs/population.md].",
)
@out_option("out/population/<problem>")
@click.option(
    "--files",
    is_flag=True,
    help="Write each worker's files and figures too (cases/<worker>/) [default: its row].",
)
@click.option(
    "--max-cases",
    type=click.IntRange(min=1),
    default=MAX_WORKERS,
    show_default=True,
    help="The most workers in all the run takes.",
)
@SOLVER_OPTION
@SET_OPTION
@batch_options(every_core=True)
def population(
    problem: str,
    n: int,
    sex: str,
    seed: int,
    correlation: float | None,
    out: Path | None,
    files: bool,
    max_cases: int,
    solver: str | None,
    sets: tuple[str, ...],
    jobs: int,
    scheduler: str | None,
    resume: bool,
    force: bool,
    quiet: bool,
) -> None:
    """Simulate N virtual workers of each sex holding the problem's task, each on a body of
    their own sex, stature and mass (ANSUR II) and strengths (the shipped spreads), and
    print the share of each sex still holding it at 1, 2, 5, 10 and 20 minutes with 95 %
    intervals, and the share for whom it is sustainable (on the file's [schedule], if any:
    no group ever at the fatigue threshold). Writes summary.csv (a row per worker),
    population.json, survival.png and held_vs_stature.png; resumable like batch. Exit
    code 1 when a worker's run is flagged (over strength at the start, say) or failed, 2 on
    bad input, 130 on Ctrl-C (finished workers are kept; rerun with --resume).

    \b
    Example:
      casadi-posture population problems/standing_wall_horizontal.toml --n 50
      casadi-posture population problems/standing_wall_horizontal.toml --n 20 \\
          --set schedule.t_on_s=60 --set schedule.t_off_s=30
    """
    out = out or Path("out", "population", Path(problem).stem)
    report = api.population(
        problem,
        out,
        n=n,
        sexes=SEXES[sex],
        seed=seed,
        correlation=correlation,
        solver=solver,
        jobs=jobs,
        scheduler=scheduler,
        resume=resume,
        force=force,
        files=files,
        max_cases=max_cases,
        overrides=parse_sets(sets),
        quiet=quiet,
    )
    batch = report.batch
    click.echo(
        f"{len(batch.rows)} workers ({batch.ran} run now, {batch.skipped} already done); "
        f"{report.summary['n_per_sex']} per sex, seed {report.summary['seed']}"
    )
    rows = []
    for sex in report.summary["sexes"].values():
        for share in sex["still_holding"]:
            shown = (
                "beyond the run"
                if share["share"] is None
                else f"{100 * share['share']:.0f} % ({100 * share['low']:.0f}-"
                f"{100 * share['high']:.0f} %)"
            )
            rows.append([sex["people"], share["minutes"], share["n"], shown])
    click.echo(table(["workers", "at (min)", "n", "still holding (95 % interval)"], rows))
    kept = [
        f"{sex['people']} {k['count']} of {k['n']}, {100 * k['share']:.0f} % "
        f"({100 * k['low']:.0f}-{100 * k['high']:.0f} %)"
        for sex in report.summary["sexes"].values()
        if (k := sex["sustainable"])["share"] is not None
    ]
    if kept:
        schedule = ", on its schedule," if report.summary["schedule"] else ""
        click.echo(
            f"sustainable{schedule} for the whole {report.summary['horizon_s']:g} s (no group "
            f"ever at the fatigue threshold):\n  {'; '.join(kept)}"
        )
    for sex in report.summary["sexes"].values():
        gave_out = ", ".join(f"{k} {v}" for k, v in sorted(sex["exhausted_region"].items()))
        click.echo(f"{sex['people']}: the region that gave out: {gave_out}")
        if sex["flagged"]:
            click.echo(
                f"FLAGGED: {sex['people']}: {sex['flagged']} of {sex['drawn']} worker(s) "
                "flagged (why: summary.csv, column flags)"
            )
        if sex["failed"]:
            click.echo(f"{sex['people']}: {sex['failed']} worker(s) failed (summary.csv)")
    if report.summary["groups_not_varied"]:
        fixed = ", ".join(report.summary["groups_not_varied"])
        click.echo(f"note: strength curves the file sets are not varied: {fixed}")
    for note in report.summary["notes"]:
        click.echo(f"note: {note}")
    click.echo(f"files: {batch.summary}, {out / 'population.json'}")
    for figure in report.figures:
        click.echo(f"figure: {figure}")
    if batch.interrupted:
        click.echo(
            f"interrupted: {len(batch.rows)} of {batch.total} workers finished and kept; "
            "rerun with --resume to run the rest",
            err=True,
        )
        raise SystemExit(INTERRUPTED)
    if batch.with_status("flagged", "failed"):
        raise SystemExit(1)
