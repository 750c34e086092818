"""The command that runs a recorded motion instead of the IK: evaluate."""

from __future__ import annotations

import functools
import time
from pathlib import Path

import click

from casadi_posture import api, interrupt
from casadi_posture.cli.common import (
    ALL_OPTION,
    FORCE_OPTION,
    SET_OPTION,
    SOLVER_OPTION,
    command_line,
    main,
    no_report_option,
    out_option,
    problem_from,
)
from casadi_posture.cli.durations import TIME
from casadi_posture.cli.runs import echo_files, report_recording, write_run
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.output.report import table
from casadi_posture.output.writable import check_writable
from casadi_posture.runs.prediction import (
    PREDICTED,
    SHOWN_DOFS,
    PredictionComparison,
    clear_prediction,
    compare_prediction,
    write_prediction,
)
from casadi_posture.static import law


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--motion",
    type=click.Path(dir_okay=False, path_type=Path),
    required=True,
    help="The recording: a .csv or .parquet file of joint angles in degrees with a time "
    "column in s (time_s or time), one column per DOF named as `describe` names it "
    "(or shoulder_flexion_r_deg, as timeline.csv has it; other names mapped by the "
    "problem's [motion.columns]); or a .c3d file of markers, mapped to the body's "
    "landmarks by the problem's [motion.markers], or a .bvh file of joint rotations mapped "
    "to its segments by [motion.bvh], turned into joint angles by the IK.",
)
@SOLVER_OPTION
@click.option(
    "--between",
    "between_s",
    type=(TIME, TIME),
    default=None,
    metavar="START END",
    help="Only the frames from START to END of the recording, times such as 12.5 or 2min "
    "(the file's time; a static calibration window may lie outside) [default: all of them].",
)
@click.option(
    "--resample",
    "resample_s",
    type=TIME,
    default=None,
    metavar="TIME",
    help="Resample the recording every this time, e.g. 0.1 or 0.1s (linear between frames) "
    "[default: the file's own frames].",
)
@click.option(
    "--repeat",
    "repeat_times",
    type=click.IntRange(min=1),
    default=None,
    help="Play the recording this many times in a row, as a work cycle.",
)
@click.option(
    "--until",
    "until_s",
    type=TIME,
    default=None,
    metavar="TIME",
    help="Play the recording as a work cycle until this time, e.g. 3600 or 1h.",
)
@out_option("out/evaluate/<problem>-<motion>")
@click.option(
    "--compare-prediction",
    "compare",
    is_flag=True,
    help="Also simulate the problem's own tasks over the same time and set the predicted "
    "postures, fatigue and endurance beside the recorded ones (OUT/predicted/, "
    "prediction.csv, prediction.json).",
)
@no_report_option("the recording in one page for a browser: the body in 3-D with a time slider")
@ALL_OPTION
@SET_OPTION
@FORCE_OPTION
def evaluate(
    problem: str,
    motion: Path,
    solver: str | None,
    between_s: tuple[float, float] | None,
    resample_s: float | None,
    repeat_times: int | None,
    until_s: float | None,
    out: Path | None,
    compare: bool,
    no_report: bool,
    show_all: bool,
    sets: tuple[str, ...],
    force: bool,
) -> None:
    """Drive the problem's body with a recorded motion instead of the IK: per frame the
    torques at the recorded posture with the problem's loads, each group's load and
    fatigue, recovery, the low back and RULA/REBA. Writes the files, figures and
    report.html of `simulate` into the output folder (new or empty, or --force).

    Nothing moves the posture: a group the model finds exhausted is an event and a flag,
    and the recording goes on. Exit code 1 when the answer needs care (a flag: a long gap
    in the recording, angles outside the body's range, a group exhausted by the model,
    the low back above the NIOSH design limit), 2 on bad input, 130 on Ctrl-C (the files
    then hold the frames so far).

    \b
    Example:
      casadi-posture evaluate problems/standing_wall_horizontal.toml \\
          --motion out/simulate/standing_wall_horizontal-active-nullspace/timeline.csv
      casadi-posture evaluate problems/seated_assembly.toml --motion shift.csv --until 3600
    """
    if repeat_times is not None and until_s is not None:
        raise ProblemError(None, "--repeat", repeat_times, "--repeat or --until, not both")
    with interrupt.deferred():
        resolved = problem_from(problem, sets=sets)
        if compare and not resolved.spec.tasks:
            expected = "at least one task to predict a posture from (--compare-prediction)"
            raise ProblemError(resolved.path, "tasks", MISSING, expected)
        out = out or Path("out", "evaluate", f"{Path(problem).stem}-{motion.stem}")
        api.check_out(out, force=force)  # before reading: a C3D file's IK takes a while
        if compare:
            check_writable(out / PREDICTED, "--out")
        started = time.perf_counter()
        recording = api.read_motion(
            resolved,
            motion,
            solver=solver,
            between_s=between_s,
            resample_s=resample_s,
            repeat_times=repeat_times,
            until_s=until_s,
        )
        read_s = time.perf_counter() - started
        clear_prediction(out)  # an earlier evaluation's comparison, not this one's
        run = api.evaluate(resolved, recording)
        shown = functools.partial(report_recording, run, law(resolved), show_all, read_s=read_s)
        files, code = write_run(run, out, command_line(), shown, report=not no_report)
        code = echo_files(files, code)
        if compare and run.stop != "interrupted":
            comparison = compare_prediction(run.result.problem, run.result)
            predicted = api.Simulation(comparison.predicted)
            extra, _ = write_run(predicted, out / PREDICTED, command_line(), report=not no_report)
            extra += write_prediction(comparison, out)
            _echo_prediction(comparison, extra)
            code = code or (1 if comparison.predicted_summary["flags"] else 0)
    raise SystemExit(code)


def _echo_prediction(comparison: PredictionComparison, files: list[Path]) -> None:
    """Print the recorded and the predicted outcomes side by side, and the DOFs whose
    postures differ most."""
    click.echo("\nrecorded beside predicted (the problem's tasks simulated over the same time):")
    rows = [[r["outcome"], r["recorded"], r["predicted"]] for r in comparison.outcomes()]
    click.echo(table(["outcome", "recorded", "predicted"], rows, digits=2))
    click.echo()
    postures = comparison.postures()[:SHOWN_DOFS]
    columns = {
        "dof": "dof",
        "recorded_first_deg": "recorded first (deg)",
        "predicted_start_deg": "predicted start (deg)",
        "recorded_mean_deg": "recorded mean (deg)",
        "predicted_mean_deg": "predicted mean (deg)",
        "rms_difference_deg": "RMS difference (deg)",
    }
    rows = [[r[k] for k in columns] for r in postures]
    click.echo(table(list(columns.values()), rows, digits=1))
    for flag in comparison.predicted_summary["flags"]:
        click.echo(f"FLAGGED (predicted): {flag}")
    click.echo("files: " + ", ".join(str(f) for f in files))
