"""The design command: task targets chosen by one NLP to maximise endurance or % capable,
or to minimise the L5/S1 compression."""

from __future__ import annotations

import math
from pathlib import Path

import click
import numpy as np

from casadi_posture import api
from casadi_posture.biomech.low_back import limits as compression_limits
from casadi_posture.cli.common import FORCE_OPTION, SET_OPTION, emit_json, main, problem_from
from casadi_posture.output.plain import dumps
from casadi_posture.output.report import fmt, table
from casadi_posture.workplace_design.answer import Design, sweep
from casadi_posture.workplace_design.objectives import OBJECTIVES, Score
from casadi_posture.workplace_design.quantities import parse_free
from casadi_posture.workplace_design.solve import design


@main.command(name="design")
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--free",
    "free",
    multiple=True,
    required=True,
    metavar="KEY=LO:HI",
    help="A task target coordinate to choose within [LO, HI] m (repeatable); "
    "KEY1,KEY2=LO:HI ties keys to one value (two hands on one shelf).",
)
@click.option(
    "--objective",
    type=click.Choice(OBJECTIVES),
    default="endurance",
    show_default=True,
    help="Maximise the task's static endurance or the share of men or women capable, or "
    "minimise the L5/S1 compression [N] (a body with a lumbar joint; the trunk's bending and "
    "twist held as at the start).",
)
@click.option(
    "--keep-levels",
    type=int,
    default=None,
    help="Keep only the first N priority levels as equalities [default: every level the "
    "IK achieves at the start].",
)
@click.option(
    "--starts",
    type=int,
    default=1,
    show_default=True,
    help="Also start the NLP from the IK at N-1 designs spread over the bounds "
    "(a local method; the best answer is kept).",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Write design.json and design.png into this folder (new or empty, or --force).",
)
@SET_OPTION
@FORCE_OPTION
def design_command(
    problem: str,
    free: tuple[str, ...],
    objective: str,
    keep_levels: int | None,
    starts: int,
    as_json: bool,
    out: Path | None,
    sets: tuple[str, ...],
    force: bool,
) -> None:
    """Choose task target coordinates (a shelf's height, a line's position) within bounds
    to maximise the task's static endurance or its share of people capable, or to minimise
    its low-back (L5/S1) compression, by one NLP over the posture and the design (IPOPT),
    the task kept and joint limits respected.
    The answer is checked by re-solving the IK with the file's solver at the design.

    Every level the IK achieves at the start is kept as an equality; the others are
    dropped (the person takes the best posture). Exit code 1 when IPOPT fails or the
    design does not keep the task, or when the IK re-solved at the design settles another
    posture than the NLP's (flagged): the gain reported is the re-solve's.

    \b
    Example:
      casadi-posture design problems/standing_shelf_box.toml \\
          --free 'tasks[2].target_m[2],tasks[3].target_m[2]=1.0:1.6'
      casadi-posture design problems/standing_shelf_box.toml --objective compression \\
          --free 'tasks[2].target_m[2],tasks[3].target_m[2]=1.0:1.6'
      casadi-posture design problems/holding_horizontal.toml \\
          --free 'tasks[0].point_m[2],tasks[1].target_m[2]=-0.5:0.1' --out out/design
    """
    resolved = problem_from(problem, sets=sets)
    bounds = parse_free(free, problem)
    if out is not None:
        api.check_out(out, force=force)
    answer = design(resolved, bounds, objective, keep_levels, starts)
    if as_json:
        emit_json(answer.to_dict())
    else:
        _echo(answer)
    if out is not None:
        files = _write(answer, out)
        if not as_json:
            click.echo("\nwrote: " + ", ".join(str(f) for f in files))
    raise SystemExit(1 if answer.flags else 0)


def _write(answer: Design, out: Path) -> list[Path]:
    """design.json and the figure: the one-key sweep, or the group loads (the compression
    for that objective)."""
    from casadi_posture.output import design_plots as plots  # imported when drawn

    out.mkdir(parents=True, exist_ok=True)
    data = out / "design.json"
    figure = out / "design.png"
    if len(answer.free) == 1:
        f = answer.free[0]
        values = np.linspace(f.lower_m, f.upper_m, plots.SWEEP_POINTS)
        points = sweep(answer, values)
        plots.plot_sweep(answer, points, figure)
        record = answer.to_dict() | {
            "sweep": [
                {"value_m": p.value_m, "task_kept": p.kept, **p.score.to_dict(answer.unit)}
                for p in points
            ]
        }
    else:
        draw = plots.plot_compression if answer.objective == "compression" else plots.plot_loads
        draw(answer, figure)
        record = answer.to_dict()
    data.write_text(dumps(record) + "\n", encoding="utf-8")
    return [data, figure]


def _signed(gain: float, digits: int) -> str:
    """A gain with its sign, or 'unlimited'."""
    return "unlimited" if math.isinf(gain) else f"{gain:+.{digits}f}"


def _niosh(compression: float) -> str:
    """Where a compression [N] lies against the NIOSH limits."""
    limit = compression_limits()
    if compression > limit["upper"]:
        return f"ABOVE the upper limit {limit['upper']:g} N"
    if compression > limit["design"]:
        return f"ABOVE the design limit {limit['design']:g} N"
    return f"below the design limit {limit['design']:g} N"


def _scores(answer: Design, rows: list[tuple[str, Score]]) -> str:
    """The objective's table: per row its value and limiting group, or its compression."""
    if answer.objective == "compression":
        return table(
            ["", "L5/S1 compression (N)", "NIOSH"],
            [[name, s.value, _niosh(s.value)] for name, s in rows],
            digits=1,
        )
    unit = "endurance (min)" if answer.objective == "endurance" else "capable (%)"
    return table(
        ["", unit, "limiting group", "region", "load (%MVC)"],
        [[name, s.value, s.group, s.region, s.load_pct_mvc] for name, s in rows],
        digits=3,
    )


def _echo(answer: Design) -> None:
    click.echo(
        f"{answer.problem.path}: design for {answer.objective}; IPOPT {answer.status}, "
        f"{answer.iterations} iterations, {answer.wall_time_s:.2f} s"
    )
    click.echo(f"levels kept: {'; '.join(answer.kept) or 'none'}")
    if answer.dropped:
        click.echo(f"levels dropped: {'; '.join(answer.dropped)}")
    click.echo()
    click.echo(
        table(
            ["free quantity", "lower (m)", "upper (m)", "start (m)", "best (m)", "at bound"],
            [
                [f.name, f.lower_m, f.upper_m, f.start_m, answer.best_m[j], answer.at_bound(j)]
                for j, f in enumerate(answer.free)
            ],
            digits=4,
        )
    )
    click.echo()
    rows = [
        ("start (IK)", answer.start),
        ("best (NLP)", answer.best),
        (f"best, IK re-solved ({answer.check_answer.ik.solver})", answer.check),
    ]
    click.echo(_scores(answer, rows))
    gain, digits = ("reduction", 1) if answer.objective == "compression" else ("gain", 3)
    ratio = "" if answer.ratio is None else f" (×{fmt(answer.ratio, 3)})"
    click.echo(
        f"\n{gain} (IK re-solved at the design): {_signed(answer.gain, digits)} "
        f"{answer.gain_unit}{ratio}"
    )
    tolerance = answer.to_dict()["check"]["tolerance"]
    verdict = "agrees" if answer.agrees else "DIFFERS"
    click.echo(
        f"re-solve check: {verdict} with the NLP's {gain} {_signed(answer.nlp_gain, digits)} "
        f"(tolerance {tolerance})"
    )
    for note in answer.notes:
        click.echo(f"note: {note}")
    for flag in answer.flags:
        click.echo(f"FLAGGED: {flag}")
