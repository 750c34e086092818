"""Commands that run holds over time: simulate, batch, whatif."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import click

from ..report import table
from .common import SOLVER_OPTION, batch_options, main, problem_from


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@SOLVER_OPTION
@click.option(
    "--strategy",
    type=click.Choice(["active", "passive"]),
    default=None,
    help="Recovery strategy [default: the file's fatigue.strategy].",
)
@click.option(
    "--r-min",
    "r_min",
    type=float,
    default=None,
    help="Minimum acceptable active-torque decrease ratio R_min (0-1).",
)
@click.option("--duration", type=float, default=None, help="Simulated time in s.")
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Output folder [default: out/simulate/<problem>-<strategy>-<solver>].",
)
def simulate(
    problem: str,
    solver: str | None,
    strategy: str | None,
    r_min: float | None,
    duration: float | None,
    out: Path | None,
) -> None:
    """Simulate holding the tasks over time: fatigue, the fatigue-reducing constraint with
    its hysteresis, recovery. Writes timeline.csv, events.csv, summary.json,
    manifest.json and figures into the output folder.

    \b
    Example:
      casadi-posture simulate problems/holding_m45.toml --strategy passive
      casadi-posture simulate problems/line_plane_hysteresis.toml --solver nullspace \\
          --duration 600 --out out/hysteresis
    """
    from ..plots import plot_simulation
    from ..results import summary, write_results
    from ..simulation import simulate as run

    given = (
        ("fatigue.strategy", strategy),
        ("fatigue.r_min", r_min),
        ("simulation.duration_s", duration),
    )
    overrides = {key: value for key, value in given if value is not None}
    resolved = problem_from(problem, overrides=overrides)
    result = run(resolved, solver)
    out = out or Path(
        "out", "simulate", f"{Path(problem).stem}-{result.settings.strategy}-{result.solver}"
    )
    files = write_results(result, out) + plot_simulation(result, out)
    report = summary(result)
    stats = report["solver_statistics"]
    click.echo(
        f"{problem}: {report['simulated_s']:.0f} s simulated, {result.solver} solver, "
        f"{report['strategy']} strategy; {stats['wall_time_s']:.2f} s wall, "
        f"{100 * (1 - stats['share_outside_ik']):.0f} % in IK, "
        f"{stats['ik_failures']} IK failures\n"
    )
    click.echo(
        table(
            [
                "half-joint",
                "initial load (%MVC)",
                "initial endurance (min)",
                "first at fatigue threshold (s)",
                "max fatigue",
            ],
            [
                [
                    g["half_joint"],
                    g["initial_load_pct_mvc"],
                    g["initial_endurance_min"],
                    g["first_fatigue_threshold_s"],
                    g["max_fatigue"],
                ]
                for g in report["half_joints"]
            ],
            digits=2,
        )
    )
    first = report["first_to_fatigue"]
    click.echo(
        f"\nfirst to fatigue: {first['half_joint']} at {first['time_s']:.0f} s"
        if first
        else "\nfirst to fatigue: none"
    )
    click.echo(f"fatigue/recovery cycles: {report['fatigue_recovery_cycles']}")
    for rec in report["recovery_postures"]:
        posture = ", ".join(f"{k} {v:.1f}°" for k, v in rec["posture_deg"].items())
        click.echo(f"  recovered at {rec['time_s']:.0f} s: {posture}")
    lost = report["task_lost"]
    click.echo(
        f"task could no longer be held at {lost['time_s']:.0f} s ({lost['half_joint']} exhausted)"
        if lost
        else "task held to the end"
    )
    click.echo("files: " + ", ".join(str(f) for f in files))


@main.command()
@click.argument("problems", nargs=-1, required=True, type=click.Path())
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    required=True,
    help="Output folder: cases/<case>/ and summary.csv.",
)
@SOLVER_OPTION
@batch_options
def batch(
    problems: tuple[str, ...],
    out: Path,
    solver: str | None,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    quiet: bool,
) -> None:
    """Simulate many problem files (folders give their *.toml): each case in its own
    folder as simulate writes it, and one summary row per case in summary.csv (and
    summary.parquet when pyarrow is installed).

    A failing case is recorded with its reason and the batch carries on. Exit code 0
    when every case succeeded, 1 when some failed, 2 for usage errors. A killed batch
    rerun with --resume redoes no finished case.

    \b
    Example:
      casadi-posture batch problems/ --out out/batch --jobs 2
      casadi-posture batch problems/ --out out/batch --jobs 2 --resume
    """
    from ..batch import cases_from_paths, run_batch

    report = run_batch(
        cases_from_paths(problems, solver),
        out,
        jobs=jobs,
        scheduler=scheduler,
        resume=resume,
        quiet=quiet,
    )
    click.echo(
        f"{len(report.rows)} cases ({report.ran} run now, {report.skipped} already "
        f"done), {len(report.failed)} failed; summary: {report.summary}"
    )
    for row in report.failed:
        click.echo(f"failed {row['case']}: {row['error']}")
    if report.failed:
        raise SystemExit(1)


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--vary",
    "varies",
    multiple=True,
    required=True,
    metavar="KEY=V1,V2,...",
    help="A problem key and its values (repeatable): loads[0].mass_kg=2.5,5, "
    "fatigue.strategy=active,passive, body.sex=male,female, solver=...",
)
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Output folder [default: out/whatif/<problem>].",
)
@click.option(
    "--static", is_flag=True, help="Answer from torques at the start posture only (no time loop)."
)
@SOLVER_OPTION
@batch_options
def whatif(
    problem: str,
    varies: tuple[str, ...],
    out: Path | None,
    static: bool,
    solver: str | None,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    quiet: bool,
) -> None:
    """What if the load, the line, the strategy, R_min, the thresholds, the body or the
    solver were different? Runs the grid of the varied keys and reports per case the
    endurance of each half-joint and of the task, the limiting muscle group, the
    fatigue/recovery cycles and the recovery posture: a table, whatif.csv and a plot
    of each outcome against each varied key.

    \b
    Example:
      casadi-posture whatif problems/holding_m45.toml --vary loads[0].mass_kg=1,2.5,5
      casadi-posture whatif problems/holding_m25.toml --vary tasks[0].elevation_deg=0,-25,-45 \\
          --vary fatigue.strategy=active,passive --jobs 2
      casadi-posture whatif problems/holding_m45.toml --vary body.mass_kg=60,73,90 --static
    """
    from ..batch import run_batch
    from ..whatif import grid, parse_vary, plot_outcomes

    parsed = [parse_vary(text) for text in varies]
    out = out or Path("out", "whatif", Path(problem).stem)
    cases = grid(problem, parsed, solver=solver, simulate=not static)
    report = run_batch(cases, out, jobs=jobs, scheduler=scheduler, resume=resume, quiet=quiet)
    shutil.copyfile(report.summary, out / "whatif.csv")
    keys = [k for k, _ in parsed]
    headers = [*keys, "limiting group", "endurance at start (min)"]
    if not static:
        headers += ["first at threshold (s)", "cycles", "task held (s)"]
    rows = []
    order = {k: [str(v) for v in values] for k, values in parsed}

    def position(row: dict[str, Any]) -> list[int]:
        given = [str(row.get("solver") if k == "solver" else row.get(k)) for k in keys]
        return [
            order[k].index(v) if v in order[k] else -1 for k, v in zip(keys, given, strict=True)
        ]

    for row in sorted(report.rows, key=position):
        if row["status"] != "ok":
            failed = [*(row.get(k) for k in keys), f"failed: {row['error']}"]
            rows.append(failed + [None] * (len(headers) - len(failed)))
            continue
        line = [
            *(row.get("solver") if k == "solver" else row.get(k) for k in keys),
            row["limiting_group"],
            row["limiting_endurance_min"],
        ]
        if not static:
            line += [row["first_fatigue_s"], row["fatigue_recovery_cycles"], row["task_held_s"]]
        rows.append(line)
    click.echo(table(headers, rows, digits=2))
    figures = plot_outcomes(report.rows, parsed, out, simulate=not static)
    click.echo(f"\ntable: {out / 'whatif.csv'}; figures: {len(figures)} in {out}")
    if report.failed:
        raise SystemExit(1)
