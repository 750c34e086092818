"""Commands on work–rest schedules: duty-cycle."""

from __future__ import annotations

from pathlib import Path

import click

from casadi_posture import api, interrupt
from casadi_posture.cli.common import (
    FORCE_OPTION,
    INTERRUPTED,
    SET_OPTION,
    SOLVER_OPTION,
    emit_json,
    main,
    problem_from,
)
from casadi_posture.cli.durations import TIME, TIMES
from casadi_posture.errors import ProblemError
from casadi_posture.output.report import table
from casadi_posture.runs.duty_cycle import (
    DEFAULT_PRECISION,
    DutyCycle,
    check_seconds,
    duty_cycles,
    span,
    table_columns,
    write_duty_cycles,
)


def _rests(values: tuple[float, ...], problem: str) -> list[float]:
    """``--t-off`` as rest times [s], each ≥ 0 and given once."""
    for value in values:
        check_seconds(value, "--t-off", problem, positive=False)
    if len(set(values)) != len(values):
        shown = ",".join(f"{v:g}" for v in values)
        raise ProblemError(problem, "--t-off", shown, "each rest time once")
    return list(values)


@main.command("duty-cycle")
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--t-off",
    "t_off",
    type=TIMES,
    required=True,
    metavar="TIME[,TIME...]",
    help="Rest per cycle (the load put down), a time: 30, 30s, 2min; a list, e.g. 0,30,1min, "
    "tabulates the sustainable hold against the rest.",
)
@click.option(
    "--horizon",
    type=TIME,
    default=None,
    metavar="TIME",
    help="Simulated time over which the threshold must not be reached, a time: 1800, 30min, "
    "4h [default: 8h, a shift; not the file's simulation.duration_s].",
)
@click.option(
    "--tolerance",
    type=TIME,
    default=None,
    metavar="TIME",
    help="Width (a time) of the bracket the bisection stops at [default: 5 s, at least one "
    "time step].",
)
@click.option(
    "--precision",
    type=float,
    default=DEFAULT_PRECISION,
    show_default=True,
    help="Relative width of the duty cycle's bracket the bisection stops at (0.05: its ends "
    "within 5 % of the lower), unless one time step is already wider.",
)
@SOLVER_OPTION
@SET_OPTION
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Also write duty_cycle.json, duty_cycle.csv and figures into this folder.",
)
@FORCE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def duty_cycle(
    problem: str,
    t_off: tuple[float, ...],
    horizon: float | None,
    tolerance: float | None,
    precision: float,
    solver: str | None,
    sets: tuple[str, ...],
    out: Path | None,
    force: bool,
    as_json: bool,
) -> None:
    """The sustainable duty cycle: with --t-off of rest per cycle (the load put
    down), the longest hold t_on per cycle with which no muscle group reaches the fatigue
    threshold (fatigue.fatigue_threshold: where the fatigue-reducing constraint would
    engage) within the horizon (an 8-hour shift unless --horizon says otherwise), found by
    bisection over simulations of the schedule.

    Prints every simulation, the bracket (the longest hold found below the threshold and
    the shortest found to reach it), the duty cycle t_on/(t_on + t_off) in %, beside it
    Potvin's (2012) shift-long guideline of acceptable effort against duty cycle (for the
    most loaded group's effort), the number of simulations and the wall time. Exit code 1
    when the answer cannot be used as it is (the task never held, IK failures), 130 on
    Ctrl-C (the bracket found so far is printed).

    \b
    Example:
      casadi-posture duty-cycle problems/holding_horizontal.toml --t-off 30
      casadi-posture duty-cycle problems/holding_horizontal.toml --t-off 0,15,30,60,120 \\
          --horizon 30min --out out/duty-cycle
    """
    rests = _rests(t_off, problem)
    for key, value in (("--horizon", horizon), ("--tolerance", tolerance)):
        if value is not None:
            check_seconds(value, key, problem, positive=True)
    with interrupt.deferred():
        resolved = problem_from(problem, sets=sets)
        resolved.hierarchy()  # a problem without tasks is refused, naming its file
        if out is not None:
            api.check_out(out, force=force)
        cycles = duty_cycles(
            resolved,
            rests,
            horizon_s=horizon,
            tolerance_s=tolerance,
            precision=precision,
            solver=solver,
        )
        files = write_duty_cycles(cycles, out) if out is not None else []
    if as_json:
        emit_json([c.summary() for c in cycles])
    else:
        _report(cycles, files)
    if any(c.verdict == "interrupted" for c in cycles) or interrupt.requested():
        raise SystemExit(INTERRUPTED)
    raise SystemExit(1 if any(c.flags for c in cycles) else 0)


def _report(cycles: list[DutyCycle], files: list[Path]) -> None:
    """The trials of each search and its answer in words; a table for several rests."""
    for cycle in cycles:
        click.echo(
            f"{cycle.problem}: rest {cycle.rest_s:g} s per cycle, over {span(cycle.horizon_s)}, "
            f"tolerance {cycle.tolerance_s:g} s and {100 * cycle.precision:g} % of the duty "
            f"cycle (time step {cycle.time_step_s:g} s); threshold: "
            f"a group's fatigue at {cycle.fatigue_threshold:g} (fatigue.fatigue_threshold)"
        )
        click.echo(
            table(
                ["t_on (s)", "reaches the threshold", "at (s)", "group", "max fatigue", "wall (s)"],
                [
                    [
                        t.t_on_s,
                        "interrupted" if t.reached is None else "yes" if t.reached else "no",
                        t.threshold_s,
                        t.half_joint or "-",
                        t.max_fatigue,
                        t.wall_time_s,
                    ]
                    for t in cycle.trials
                ],
                digits=2,
            )
        )
        for line in answer_lines(cycle):
            click.echo(line)
        click.echo()
    if len(cycles) > 1:
        columns = table_columns(cycles)
        shown = {
            "rest_s": "rest (s)",
            "verdict": "verdict",
            "sustainable_t_on_s": "sustainable t_on (s)",
            "failing_t_on_s": "failing t_on (s)",
            "duty_cycle_pct": "duty cycle (%)",
        }
        rows = [list(row) for row in zip(*(columns[k] for k in shown), strict=True)]
        click.echo(table(list(shown.values()), rows, digits=1))
    if files:
        click.echo("files: " + ", ".join(str(f) for f in files))


def answer_lines(cycle: DutyCycle) -> list[str]:
    """A search's answer in words: the bracket and duty cycle, or why there is none."""
    rest, verdict = cycle.rest_s, cycle.verdict
    failing = next((t for t in cycle.trials if t.t_on_s == cycle.failing_t_on_s), None)
    where = f" ({failing.half_joint} at {failing.threshold_s:g} s)" if failing else ""
    over = span(cycle.horizon_s)
    if verdict == "continuous":
        lines = [
            f"sustainable for {over} held continuously: the hold never reaches the threshold "
            "(duty cycle 100 %)"
        ]
    elif verdict == "none":
        fail = cycle.failing_t_on_s
        lines = [
            f"no duty cycle works for {over}: even {fail:g} s on per {fail + rest:g} s cycle "
            f"(one time step of hold, {rest:g} s of rest) reaches the threshold{where}"
        ]
    elif verdict == "never_held":
        lines = ["task never held: level 1 not achieved at the start"]
    elif verdict == "interrupted":
        lines = [
            "interrupted: bracket so far "
            f"[{_or_dash(cycle.sustainable_t_on_s)}, {_or_dash(cycle.failing_t_on_s)}] s on "
            f"per cycle, over {over}"
        ]
    else:
        lines = _bracket_lines(cycle, where)
    guideline = cycle.guideline()
    if guideline is not None and verdict != "never_held":
        lines.append(potvin_line(guideline, cycle.duty_cycle_pct))
    lines.append(f"{len(cycle.trials)} simulations, {cycle.wall_time_s:.2f} s wall")
    return lines + [f"FLAGGED: {flag}" for flag in cycle.flags]


def potvin_line(guideline: dict, duty_cycle_pct: float | None) -> str:
    """Potvin's guideline beside our duty cycle, in words."""
    line = (
        f"Potvin 2012, the effort workers accept for a shift (upper-limb tasks, ±"
        f"{guideline['rms_difference_pct_mvc']:g} %MVC):\n  {guideline['half_joint']} at "
        f"{guideline['effort_pct_mvc']:.1f} %MVC is acceptable up to a "
        f"{guideline['acceptable_duty_cycle_pct']:.1f} % duty cycle"
    )
    if guideline["acceptable_effort_at_duty_cycle_pct_mvc"] is not None:
        line += (
            f"; at our {duty_cycle_pct:.1f} % it accepts "
            f"{guideline['acceptable_effort_at_duty_cycle_pct_mvc']:.1f} %MVC"
        )
    if not guideline["region_in_guideline_data"]:
        line += f" (the {guideline['region']} is outside the guideline's data)"
    return line


def _bracket_lines(cycle: DutyCycle, where: str) -> list[str]:
    """The bracket in words: the longest hold found sustainable over the horizon, the
    shortest found not, their duty cycles, and what limits the bracket's width."""
    ok, fail, rest = cycle.sustainable_t_on_s, cycle.failing_t_on_s, cycle.rest_s
    low, high = cycle.duty_cycle_bracket_pct or (cycle.duty_cycle_pct, cycle.duty_cycle_pct)
    line = (
        f"not sustainable: {fail:g} s on per {fail + rest:g} s cycle ({high:.1f} %) reaches "
        f"the threshold{where}; the limit lies between the two"
    )
    if cycle.step_limited:
        line += (
            f"; the bracket is one time step ({cycle.time_step_s:g} s) wide: a shorter "
            "simulation.time_step_s narrows it"
        )
    return [
        f"sustainable for {span(cycle.horizon_s)}: up to {ok:g} s on per {ok + rest:g} s cycle "
        f"({rest:g} s of rest), a {low:.1f} % duty cycle",
        line,
    ]


def _or_dash(value: float | None) -> str:
    return "-" if value is None else f"{value:g}"
