"""Commands on the IK solvers: solve, compare."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from casadi_posture import api
from casadi_posture.cli.common import (
    ALL_OPTION,
    FORCE_OPTION,
    SET_OPTION,
    SOLVER_OPTION,
    echo_free_dofs,
    echo_torques,
    emit_json,
    main,
    no_report_option,
    problem_from,
)
from casadi_posture.ik.result import ACHIEVED_TOLERANCE
from casadi_posture.output import low_back
from casadi_posture.output.answer import answer_json
from casadi_posture.output.report import table
from casadi_posture.output.scores import lines
from casadi_posture.runs.compare import MAX_STARTS, Starts, rows

NO_REPORT_OPTION = no_report_option(
    "one page for a browser: the postures in 3-D, the summary, the loads and the tables"
)


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@SOLVER_OPTION
@SET_OPTION
@ALL_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Folder for solve.json (what --json prints) and report.html [default: print only].",
)
@NO_REPORT_OPTION
@FORCE_OPTION
def solve(
    problem: str,
    solver: str | None,
    sets: tuple[str, ...],
    show_all: bool,
    as_json: bool,
    out: Path | None,
    no_report: bool,
    force: bool,
) -> None:
    """Solve the prioritized IK of a problem from its posture_deg; print the posture,
    the residual of each priority level and whether it was achieved, the active
    constraints and the torques there. With --out, also write solve.json and report.html
    (one page that opens offline in a browser: the start and the answer in 3-D, the
    summary, the loads; not with --no-report).

    Exits with code 1, saying why, when the answer cannot be used as it is: the solver
    failed (its status is printed), level 1 was not achieved (residual above
    0.0001 m or rad: out of reach, or blocked by a joint limit) or a muscle group would
    need more than its strength.

    \b
    Example:
      casadi-posture solve problems/line_plane_hysteresis.toml
      casadi-posture solve problems/line_plane_hysteresis.toml --solver nullspace --json
      casadi-posture solve problems/standing_shelf_box.toml --out out/shelf
    """
    resolved = problem_from(problem, sets=sets)
    resolved.hierarchy()  # a problem without tasks is refused, naming its file
    if out is not None:
        api.check_out(out, force=force)
    answer = api.solve(resolved, solver)
    result = answer.ik
    levels = [level.__dict__ for level in answer.levels]
    written = [] if out is None else api.write_solve(answer, out, report=not no_report, force=force)
    if as_json:
        emit_json(answer_json(answer, problem))
    else:
        click.echo(
            f"{problem}: {result.solver}, status {result.status}, {result.iterations} "
            f"iterations, {1e3 * result.wall_time_s:.2f} ms\n"
        )
        click.echo(
            table(
                ["level", "tasks", "residual", "unit", f"achieved (≤ {ACHIEVED_TOLERANCE:g})"],
                [
                    [
                        lv["level"],
                        lv["tasks"],
                        f"{lv['residual']:.3g}",
                        lv["unit"],
                        level.outcome,
                    ]
                    for lv, level in zip(levels, answer.levels, strict=True)
                ],
            )
        )
        limits = ", ".join(result.at_limits) or "none"
        click.echo(f"\njoints at a limit: {limits}")
        echo_free_dofs(answer.problem)
        click.echo()
        echo_torques(answer, show_all)
        for line in [*lines(answer.problem, answer.scores), *low_back.lines(answer.low_back)]:
            click.echo(line)
        for path in written:
            click.echo(f"written: {path}")
        for flag in answer.flags:
            click.echo(f"FLAGGED: {flag}")
    if answer.flags:
        raise SystemExit(1)


@main.command(name="compare")
@click.argument("problems", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Folder for compare.csv and report.html.",
)
@click.option(
    "--starts",
    type=click.IntRange(1, MAX_STARTS),
    default=None,
    help=f"Also solve from this many random starts within the joint limits (1 to {MAX_STARTS}) "
    "and count how many agree, reach the task, stop at a local minimum or differ.",
)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Seed of the random starts (the same seed, the same starts).",
)
@NO_REPORT_OPTION
@SET_OPTION
@FORCE_OPTION
def compare_command(
    problems: tuple[str, ...],
    out: Path | None,
    starts: int | None,
    seed: int,
    no_report: bool,
    sets: tuple[str, ...],
    force: bool,
) -> None:
    """Solve each problem with both IK solvers from the same start and compare them:
    residual per level, largest joint difference, wall time, status, and a verdict
    that says why they disagree (two posture families, one stopping short of a level).
    When both miss a level, the verdict says whether they share a local minimum (another
    start reaches the level; the joints they hold at a limit) or the level is out of reach,
    and on which evidence: the chain's reach, or no random start reaching it.

    With --starts N, both solvers also solve from N starts drawn uniformly within the
    joint limits (--seed): per problem, how many starts agree, reach the task, stop at a
    local minimum or at a target out of reach, how many differ, and the worst
    disagreement.

    With --out, writes compare.csv and report.html (one page that opens offline in a
    browser: a row per problem; a click on it shows the start and both solvers' postures
    in 3-D, the verdict and the tables; not with --no-report).

    Problems without tasks are skipped. Exits with code 1 when any problem disagrees, a
    solver fails, or level 1 is not achieved (residual above 0.0001 m or rad), from the
    file's start or, with --starts, the solvers differ from a random start.

    \b
    Example:
      casadi-posture compare problems/*.toml --out out/compare
      casadi-posture compare problems/holding_*.toml --starts 20
    """
    if out is not None:
        api.check_out(out, force=force)
    table_rows: list[dict[str, object]] = []
    flagged, compared = [], []
    for path in problems:
        resolved = problem_from(path, sets=sets)
        if not resolved.tasks:
            click.echo(f"skipped {path}: no tasks")
            continue
        comparison = api.compare(resolved, starts or 0, seed)
        flags = []
        if not comparison.agree:
            flags.append(f"the solvers disagree: {comparison.verdict}")
        unreached = [
            r.solver for r in (comparison.nullspace, comparison.lexicographic) if not r.achieved[0]
        ]
        if unreached:
            flags.append(f"level 1 not achieved by {' and '.join(unreached)}")
        if comparison.starts is not None and comparison.starts.differ:
            flags.append(
                f"the solvers differ from {comparison.starts.differ} of "
                f"{comparison.starts.count} random starts"
            )
        flagged += [f"{path}: {flag}" for flag in flags]
        compared.append((resolved, comparison, flags))
        table_rows += rows(comparison)
    headers = [
        "problem",
        "level",
        "tasks",
        "unit",
        "residual nullspace",
        "residual lexicographic",
        "max joint diff (deg)",
        "time nullspace (ms)",
        "time lexicographic (ms)",
        "verdict",
    ]
    click.echo(
        table(
            headers,
            [
                [
                    r["problem"],
                    r["level"],
                    r["tasks"],
                    r["unit"],
                    f"{r['residual_nullspace']:.3g}",
                    f"{r['residual_lexicographic']:.3g}",
                    f"{r['max_joint_difference_deg']:.2g}",
                    r["time_nullspace_ms"],
                    r["time_lexicographic_ms"],
                    r["verdict"],
                ]
                for r in table_rows
            ],
            digits=2,
        )
    )
    for _, comparison, _ in compared:
        if comparison.starts is not None:
            echo_starts(comparison.problem, comparison.starts)
    if out is not None:
        written = api.write_compare(compared, out, report=not no_report, force=True)
        click.echo("\n" + "\n".join(f"written: {path}" for path in written))
    for line in flagged:
        click.echo(f"FLAGGED: {line}")
    if flagged:
        raise SystemExit(1)


#: The differing random starts ``compare --starts`` prints per problem.
SHOWN_DIFFERENCES = 5


def echo_starts(problem: str, starts: Starts) -> None:
    """A problem's random starts in one line, then the first differing ones (their number in
    the seeded draw, from 1, their angles [deg] on a small body, their verdict)."""
    click.echo(f"\n{problem}: {starts.line()}")
    differing = [(i, c) for i, c in enumerate(starts.comparisons, 1) if not c.agree]
    for i, c in differing[:SHOWN_DIFFERENCES]:
        angles = ", ".join(f"{a:.1f}" for a in np.degrees(c.start)) if c.start.size <= 3 else ""
        at = f" ({angles} deg)" if angles else ""
        click.echo(f"  start {i}{at}: {c.verdict}")
    if len(differing) > SHOWN_DIFFERENCES:
        click.echo(f"  ... and {len(differing) - SHOWN_DIFFERENCES} more differing starts")
