"""Commands that run holds over time: simulate, batch, whatif."""

from __future__ import annotations

import functools
import hashlib
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click
import numpy as np

from casadi_posture import api, interrupt
from casadi_posture.cli.common import (
    ALL_OPTION,
    FORCE_OPTION,
    INTERRUPTED,
    SET_OPTION,
    SOLVER_OPTION,
    batch_options,
    command_line,
    echo_free_dofs,
    main,
    no_report_option,
    out_option,
    parse_sets,
    problem_from,
    shown_groups,
)
from casadi_posture.cli.durations import TIME
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.output.low_back import run_lines as low_back_lines
from casadi_posture.output.movie_formats import WRITERS, check_format
from casadi_posture.output.outcome import outcome_lines, time_text
from casadi_posture.output.report import table
from casadi_posture.output.results import SHOWN_RECOVERIES
from casadi_posture.output.run_files import MOST_WORKERS, Writers, default_workers
from casadi_posture.output.run_files import write_run as files_of_run
from casadi_posture.output.scores import run_lines
from casadi_posture.output.writable import check_writable
from casadi_posture.problem import load_problem
from casadi_posture.runs.manifest import RecordingRead, read_manifest
from casadi_posture.runs.whatif import MAX_CASES
from casadi_posture.static import law


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
@click.option(
    "--duration",
    type=TIME,
    default=None,
    metavar="TIME",
    help="Simulated time, a time: 600, 10min, 2h [default: the file's simulation.duration_s].",
)
@out_option("out/simulate/<problem>-<strategy>-<solver>")
@click.option(
    "--animate",
    type=click.Choice(list(WRITERS)),
    is_flag=False,
    flag_value="gif",
    default=None,
    help="Also write animation.gif (or, --animate mp4, animation.mp4: needs ffmpeg) of the "
    "stick figure over the run. Put it after PROBLEM or write --animate=gif.",
)
@no_report_option(
    "the run in one page for a browser: the body in 3-D with a time slider, the curves, the summary"
)
@click.option(
    "--no-figures",
    is_flag=True,
    help="Do not draw the PNG figures (the tables, summary and manifest are written; a "
    "script that reads only the numbers saves about 0.7 s on a 29-DOF body).",
)
@click.option(
    "--jobs",
    type=click.IntRange(min=1),
    default=default_workers(),
    help="Processes that write the files and draw the figures side by side, on Linux (1: "
    f"one after the other in this one) [default: the cores, at most {MOST_WORKERS}; "
    f"{default_workers()} here].",
)
@ALL_OPTION
@SET_OPTION
@FORCE_OPTION
def simulate(
    problem: str,
    solver: str | None,
    strategy: str | None,
    r_min: float | None,
    duration: float | None,
    out: Path | None,
    animate: str | None,
    no_report: bool,
    no_figures: bool,
    jobs: int,
    show_all: bool,
    sets: tuple[str, ...],
    force: bool,
) -> None:
    """Simulate holding the tasks over time: fatigue, the fatigue-reducing constraint with
    its hysteresis, recovery. Writes timeline.csv (and .parquet), events.csv,
    summary.json, manifest.json, figures (not with --no-figures) and report.html (one page
    that opens offline in a browser: the body in 3-D with a time slider, the curves and the
    summary; not with --no-report) into the output folder, which must be new or empty (or --force);
    `casadi-posture rerun OUT/manifest.json` repeats the run.

    The run ends at its duration, when a muscle group is exhausted (fatigue 1, or a load
    above its strength), or at once when level 1 cannot be achieved at the start. Exit
    code 1 when the answer cannot be used as it is (the task was never held, the start
    is over strength, or no solver converged on some step), 130 on Ctrl-C: the files
    then hold the steps run so far, marked as interrupted.

    \b
    Example:
      casadi-posture simulate problems/holding_m45.toml --strategy passive
      casadi-posture simulate problems/line_plane_hysteresis.toml --solver nullspace \\
          --duration 600 --set fatigue.recovery_law=3cc_r --out out/hysteresis
      casadi-posture simulate problems/holding_m45.toml --animate
    """
    given = (
        ("fatigue.strategy", strategy),
        ("fatigue.r_min", r_min),
        ("simulation.duration_s", duration),
    )
    overrides = {key: value for key, value in given if value is not None}
    if animate is not None:
        check_format(animate)
    with interrupt.deferred():
        resolved = problem_from(problem, overrides=overrides, sets=sets)
        name = solver or resolved.spec.solver.name
        out = out or Path(
            "out", "simulate", f"{Path(problem).stem}-{resolved.spec.fatigue.strategy}-{name}"
        )
        api.check_out(out, force=force)
        draws = not (no_figures and no_report)
        with Writers(_workers(jobs), resolved, draws=draws) as writers:
            run = api.simulate(resolved, solver)
            files, code = write_run(
                run,
                out,
                command_line(),
                functools.partial(_report, run, law(resolved), show_all),
                report=not no_report,
                figures=not no_figures,
                workers=writers.workers,
                writers=writers,
            )
        if animate is not None:
            drawn = run.animate(out / f"animation.{animate}", force=True)
            files += [drawn] if drawn else []
            if drawn is None:
                why = "Ctrl-C" if interrupt.requested() else "no step was run"
                click.echo(f"animation: not written ({why})", err=True)
    raise SystemExit(echo_files(files, code))


@main.command()
@click.argument("manifest", type=click.Path(dir_okay=False, exists=False))
@out_option("the manifest's folder + '-rerun'")
@FORCE_OPTION
def rerun(manifest: str, out: Path | None, force: bool) -> None:
    """Repeat the simulation (or the evaluation of a recording) a manifest.json records (the
    problem's data after its overrides, the solver; the recording, unchanged, and how it was
    read) and check that its summary.json is the same, byte for byte, as the one beside the
    manifest. Exit code 1 when it differs.

    \b
    Example:
      casadi-posture rerun out/simulate/holding_m45-active-lexicographic/manifest.json
    """
    path = Path(manifest)
    record = read_manifest(path)
    out = out or path.parent.with_name(path.parent.name + "-rerun")
    check_writable(out)  # before resolving it: a loop of symbolic links does not resolve
    if out.resolve() == path.parent.resolve():  # it would be compared with itself
        expected = "a folder apart from the manifest's (the rerun is compared with it)"
        raise ProblemError(None, "--out", str(out), expected)
    with interrupt.deferred():
        api.check_out(out, force=force)
        try:
            resolved = api.from_dict(record.problem_data, record.problem_path)
        except ProblemError as error:
            if error.key is None:
                raise ProblemError(path, "problem_data", MISSING, error.expected) from None
            key = f"problem_data.{error.key}"
            raise ProblemError(path, key, error.value, error.expected) from None
        recording = record.recording
        with Writers(_workers(None), resolved) as writers:
            if recording is None:
                run = api.simulate(resolved, record.solver)
            else:
                options = recording.options()
                run = api.evaluate(resolved, _recording(path, recording), **options)
            report = _report if recording is None else report_recording
            shown = functools.partial(report, run, law(resolved))
            files, code = write_run(run, out, command_line(), shown, writers=writers)
    code = echo_files(files, code)
    original = path.parent / "summary.json"
    if not original.exists():
        click.echo(f"FLAGGED: no summary.json beside {path}: the rerun was not compared")
        raise SystemExit(1)
    same = original.read_bytes() == (out / "summary.json").read_bytes()
    click.echo(f"summary.json {'identical to' if same else 'DIFFERS from'} {original}")
    raise SystemExit(code or (0 if same else 1))


def _recording(path: Path, recorded: RecordingRead) -> Path:
    """The motion file an evaluate manifest (``path``) records, as it was: a file that is
    gone or has changed since is a one-line error."""
    source = Path(recorded.source)
    if not source.is_file():
        raise ProblemError(path, "recording.source", str(source), "the recording, still there")
    sha256 = hashlib.sha256(source.read_bytes()).hexdigest()
    if sha256 != recorded.sha256:
        expected = f"the recording as it was (SHA-256 {recorded.sha256[:12]}…, now {sha256[:12]}…)"
        raise ProblemError(path, "recording.source", str(source), expected)
    return source


def write_run(
    run: api.Simulation,
    out: Path,
    command: list[str],
    shown: Callable[[], int] | None = None,
    *,
    report: bool = True,
    figures: bool = True,
    workers: int | None = None,
    writers: Writers | None = None,
) -> tuple[list[Path], int]:
    """The run's files, (with ``figures``) its figures and (with ``report``) report.html,
    written side by side by the ``writers`` forked before the run, else by ``workers``
    processes forked now (default: the cores, at most 4), while ``shown`` prints the run;
    the files and the exit code ``shown`` gives (0 without it). A report that cannot be
    written is said on stderr and the run's other files are kept."""
    codes: list[int] = [] if shown is not None else [0]
    written = files_of_run(
        run.result,
        out,
        command=command,
        figures=figures,
        report=report,
        workers=_workers(workers),
        writers=writers,
        meanwhile=None if shown is None else lambda: codes.append(shown()),
    )
    if written.report_missing is not None:
        click.echo(f"report.html: not written ({written.report_missing})", err=True)
    return written.paths, codes[0]


def echo_files(files: list[Path], code: int) -> int:
    """Print the files written; the exit code: ``code``, or Ctrl-C's when it came while
    they were written."""
    click.echo("files: " + ", ".join(str(f) for f in files))
    return INTERRUPTED if interrupt.requested() else code


def _workers(given: int | None) -> int:
    """The processes that write a run's files: ``given``, else the cores, at most 4."""
    return default_workers() if given is None else given


def _report(run: api.Simulation, recovery_law: str, show_all: bool = False) -> int:
    """Print what simulate and rerun show (on a large body the most loaded half-joints,
    unless ``show_all``) but the files; their exit code."""
    result = run.result
    problem = str(result.problem.path)
    if result.timeline.time.size == 0:  # stopped (Ctrl-C) before its first step
        click.echo(f"{problem}: no step was run ({result.stop}); nothing to show")
        return INTERRUPTED if result.stop == "interrupted" or interrupt.requested() else 1
    report = run.summary()
    stats = report["solver_statistics"]
    click.echo(
        f"{problem}: {report['simulated_s']:g} of {report['duration_s']:g} s simulated, "
        f"{result.solver} solver, {result.settings.describe()}; {result.wall_time_s:.2f} s "
        f"wall, {100 * result.ik_time_s / max(result.wall_time_s, 1e-12):.0f} % in IK, "
        f"{stats['ik_fallbacks']} steps by the other solver, {stats['ik_failures']} IK failures, "
        f"{stats['ik_reused']} unchanged steps kept their posture"
    )
    echo_free_dofs(result.problem)
    click.echo(f"recovery law: {recovery_law}")
    click.echo(f"endurance rule: {report['endurance_rule']}\n")
    groups = report["half_joints"]
    keep = shown_groups(
        [max(g["initial_load_pct_mvc"], 100 * g["max_fatigue"]) for g in groups],
        [g["initial_verdict"] == "over strength" for g in groups],
        show_all,
    )
    click.echo(
        table(
            [
                "half-joint",
                "initial load (%MVC)",
                "initial endurance (min)",
                "at start",
                "first at fatigue threshold (s)",
                "max fatigue",
            ],
            [
                [
                    g["half_joint"],
                    g["initial_load_pct_mvc"],
                    _minutes(g["initial_endurance_min"], g["initial_verdict"]),
                    g["initial_verdict"],
                    g["first_fatigue_threshold_s"],
                    g["max_fatigue"],
                ]
                for g in (groups[k] for k in keep)
            ],
            digits=2,
        )
    )
    hidden = [groups[k] for k in range(len(groups)) if k not in keep]
    if hidden:
        load = max(g["initial_load_pct_mvc"] for g in hidden)
        tired = max(g["max_fatigue"] for g in hidden)
        click.echo(
            f"... {len(hidden)} more half-joints start at most at {load:.1f} %MVC and reach at "
            f"most {tired:.2f} fatigue; --all prints every row"
        )
    click.echo()
    return echo_outcome(run, report, show_all)


def echo_outcome(run: api.Simulation, report: dict[str, Any], show_all: bool = False) -> int:
    """Print a run's outcome (its ``summary``: what tired and gave out, recoveries,
    plausibility, RULA/REBA, the low back, the flags); its exit code."""
    result = run.result
    for line in outcome_lines(report):
        click.echo(line)
    recoveries = report["recovery_postures"]
    names, first = result.problem.body.dof_names, np.degrees(result.timeline.q[0])
    start = {name: float(angle) for name, angle in zip(names, first, strict=True)}
    for rec in recoveries[:SHOWN_RECOVERIES]:
        rest = " (during a rest: the last held posture)" if rec.get("phase") == "rest" else ""
        click.echo(
            f"  recovered at {time_text(rec['time_s'])}{rest}: "
            f"{moved(start, rec['posture_deg'], show_all)}"
        )
    if len(recoveries) > SHOWN_RECOVERIES:
        click.echo(f"  ... and {len(recoveries) - SHOWN_RECOVERIES} more in summary.json")
    plausible = report["plausibility"]
    shown = plausible["postures"][:SHOWN_RECOVERIES] + plausible["postures"][-1:]
    for posture in dict.fromkeys(p["summary"] for p in shown):
        click.echo(f"  plausibility at the {posture}")
    for held in plausible["held_at_limits"]:
        click.echo(
            f"  {held['dof']} rests on its {held['limit_deg']:g}° limit for {held['seconds']:g} s"
        )
    for line in run_lines(report["rula_reba"]):
        click.echo(line)
    for line in low_back_lines(report["low_back"]):
        click.echo(line)
    for flag in report["flags"]:
        click.echo(f"FLAGGED: {flag}")
    if result.stop == "interrupted" or interrupt.requested():
        return INTERRUPTED
    return 1 if report["flags"] else 0


def report_recording(
    run: api.Simulation,
    recovery_law: str,
    show_all: bool = False,
    *,
    read_s: float | None = None,
) -> int:
    """Print what evaluate shows: the recording (read in ``read_s`` [s] wall, if given), the
    groups' loads over it (on a large body the most loaded, unless ``show_all``), the
    outcome; its exit code."""
    result, report = run.result, run.summary()
    recorded = report["recording"]
    read = "" if read_s is None else f"read in {read_s:.2f} s, "
    click.echo(
        f"{result.problem.path} driven by {recorded['source']}: {recorded['frames']} frames, "
        f"{recorded['first_time_s']:g} to {recorded['last_time_s']:g} s; {read}"
        f"replayed in {result.wall_time_s:.2f} s wall"
    )
    for note in recorded["notes"]:
        click.echo(f"  {note}")
    fit = recorded["fit_residuals"]
    if fit:
        unit, scale, shown = ("deg", 1.0, "°") if recorded["kind"] == "bvh" else ("m", 1e3, " mm")
        worst = max(fit, key=lambda k: fit[k][f"max_{unit}"])
        median = max(v[f"median_{unit}"] for v in fit.values())
        click.echo(
            f"  IK fit of the {recorded['kind']} file ({len(fit)} targets): median residual at "
            f"most {median * scale:.1f}{shown}, largest {fit[worst][f'max_{unit}'] * scale:.1f}"
            f"{shown} ({worst} at {fit[worst]['max_time_s']:g} s); per frame in timeline.csv"
        )
    click.echo(f"recovery law: {recovery_law}")
    click.echo(f"endurance rule: {report['endurance_rule']}\n")
    groups = report["half_joints"]
    keep = shown_groups(
        [max(g["peak_load_pct_mvc"], 100 * g["max_fatigue"]) for g in groups],
        [g["peak_load_pct_mvc"] > 100 for g in groups],
        show_all,
    )
    header = [
        "half-joint",
        "mean load (%MVC)",
        "peak load (%MVC)",
        "first at fatigue threshold (s)",
        "max fatigue",
        "final fatigue",
    ]
    rows = [
        [
            g["half_joint"],
            g["mean_load_pct_mvc"],
            g["peak_load_pct_mvc"],
            g["first_fatigue_threshold_s"],
            g["max_fatigue"],
            g["final_fatigue"],
        ]
        for g in (groups[k] for k in keep)
    ]
    click.echo(table(header, rows, digits=2))
    hidden = [g for k, g in enumerate(groups) if k not in keep]
    if hidden:
        peak = max(g["peak_load_pct_mvc"] for g in hidden)
        click.echo(
            f"... {len(hidden)} more half-joints peak at most at {peak:.1f} %MVC; "
            "--all prints every row"
        )
    click.echo()
    return echo_outcome(run, report, show_all)


def _minutes(value: float | None, verdict: str | None) -> float | None:
    """An endurance for the table: unlimited shows as inf."""
    return math.inf if value is None and verdict is not None else value


#: Joints a recovery line names (those that moved most from the start).
SHOWN_MOVES = 4
#: A joint that moved less than this from the start is not named [deg].
MOVED_DEG = 1.0


def moved(start: dict[str, float], posture: dict[str, float], show_all: bool = False) -> str:
    """The joints of ``posture`` [deg] that moved most from ``start`` [deg], as
    'shoulder_flexion_r 18.8 → -28.9°' (every joint with ``show_all``), and how many others
    stayed within ``MOVED_DEG``."""
    change = {k: posture[k] - start[k] for k in posture}
    ranked = sorted(change, key=lambda k: -abs(change[k]))
    named = ranked if show_all else [k for k in ranked[:SHOWN_MOVES] if abs(change[k]) >= MOVED_DEG]
    parts = [f"{k} {start[k]:.1f} → {posture[k]:.1f}°" for k in named]
    rest = len(posture) - len(named)
    if rest and not show_all:
        largest = max((abs(change[k]) for k in ranked[len(named) :]), default=0.0)
        parts.append(f"{rest} other joints within {max(largest, 0.0):.1f}°")
    return ", ".join(parts) if parts else "the start posture"


#: --no-report of batch and what-if.
NO_GRID_REPORT = click.option(
    "--no-report",
    "no_report",
    is_flag=True,
    help="Write neither report.html (every case's row in one sortable page, each case "
    "linked to its own) nor each simulated case's report.html.",
)


@main.command()
@click.argument("problems", nargs=-1, required=True, type=click.Path())
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    required=True,
    help="Output folder: cases/<case>/, summary.csv and run.json.",
)
@SOLVER_OPTION
@SET_OPTION
@NO_GRID_REPORT
@batch_options
def batch(
    problems: tuple[str, ...],
    out: Path,
    solver: str | None,
    sets: tuple[str, ...],
    no_report: bool,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    force: bool,
    quiet: bool,
) -> None:
    """Simulate many problem files (folders give their *.toml): each case in its own
    folder as simulate writes it, and one summary row per case in summary.csv (and
    summary.parquet when pyarrow is installed).

    A case's status is ok; flagged when its answer cannot be used as it is (level 1 not
    reached, a group over strength at the start, a solver failure: see its flags);
    failed, with a one-line reason, when it could not run; skipped when the problem has
    no tasks. The batch always carries on. Exit code 0 when every case is ok or skipped,
    1 when some are flagged or failed, 2 for usage errors, 130 on Ctrl-C (finished cases
    are kept; rerun with --resume).

    \b
    Example:
      casadi-posture batch problems/ --out out/batch --jobs 2
      casadi-posture batch problems/ --out out/batch --jobs 2 --resume
    """
    report = api.batch(
        problems,
        out,
        solver=solver,
        jobs=jobs,
        scheduler=scheduler,
        resume=resume,
        force=force,
        overrides=parse_sets(sets),
        report=not no_report,
        quiet=quiet,
    )
    counts = ", ".join(
        f"{len(report.with_status(status))} {status}"
        for status in ("ok", "flagged", "failed", "skipped")
    )
    click.echo(
        f"{len(report.rows)} cases ({report.ran} run now, {report.skipped} already done): "
        f"{counts}; summary: {report.summary}"
    )
    for row in report.with_status("flagged"):
        click.echo(f"flagged {row['case']}: {row['flags']}")
    for row in report.with_status("failed"):
        click.echo(f"failed {row['case']}: {row['error']}")
    for row in report.with_status("skipped"):
        click.echo(f"skipped {row['case']}: {row['error']}")
    _finish(report)


def _finish(report: Any) -> None:
    """Exit 130 after Ctrl-C, 1 when a case is flagged or failed."""
    if report.interrupted:
        click.echo(
            f"interrupted: {len(report.rows)} of {report.total} cases finished and kept; "
            "rerun with --resume to run the rest",
            err=True,
        )
        raise SystemExit(INTERRUPTED)
    if report.with_status("flagged", "failed"):
        raise SystemExit(1)


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--vary",
    "varies",
    multiple=True,
    required=True,
    metavar="KEY=V1,V2,...",
    help="A problem key and its values (repeatable): 'loads[0].mass_kg=2.5,5' (quoted: "
    "shells read [0] as a pattern), "
    "fatigue.strategy=active,passive, body.sex=male,female, solver=...; "
    "'KEY1,KEY2=V1,...' ties keys to one value (both halves of a load).",
)
@out_option("out/whatif/<problem>")
@click.option(
    "--static", is_flag=True, help="Answer from torques at the start posture only (no time loop)."
)
@click.option(
    "--max-cases",
    type=click.IntRange(min=1),
    default=MAX_CASES,
    show_default=True,
    help="Refuse a larger grid (a guard against a typo that would start a huge run).",
)
@click.option(
    "--paired",
    is_flag=True,
    help="Pair the varied values instead of a full grid: the i-th value of every --vary "
    "together (lists of one length), e.g. a small woman against a tall man.",
)
@SOLVER_OPTION
@SET_OPTION
@NO_GRID_REPORT
@batch_options
def whatif(
    problem: str,
    varies: tuple[str, ...],
    out: Path | None,
    static: bool,
    max_cases: int,
    paired: bool,
    solver: str | None,
    sets: tuple[str, ...],
    no_report: bool,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    force: bool,
    quiet: bool,
) -> None:
    """What if the load, the line, the strategy, R_min, the thresholds, the body or the
    solver were different? Runs the grid of the varied keys and reports per case whether
    level 1 was reached, the limiting muscle group at the start (the shortest endurance)
    and, simulated, the group actually exhausted, the fatigue/recovery cycles and how
    long the task was held (≥: held to the end of the run), the worst RULA and REBA
    (docs/rula_reba.md) and the (peak) low-back compression (docs/low_back.md): a table,
    whatif.csv and a figure of each answer against the first varied key, one line per
    value of the others. KEY1,KEY2=V1,... ties keys of one unit to one value (both hands'
    heights, both halves of a load): one axis.

    Every combination is validated before anything runs. Exit codes as for batch: 1
    when a case is flagged (not reached, over strength, solver failure) or failed.

    \b
    Example:
      casadi-posture whatif problems/holding_m45.toml --vary 'loads[0].mass_kg=1,2.5,5'
      casadi-posture whatif problems/holding_m25.toml --vary 'tasks[0].elevation_deg=0,-25,-45' \\
          --vary fatigue.strategy=active,passive --jobs 2
      casadi-posture whatif problems/holding_m45.toml --static --paired \\
          --vary body.sex=female,male --vary body.stature_m=1.52,1.87
      casadi-posture whatif problems/standing_shelf_box.toml --static \\
          --vary 'tasks[2].target_m[2],tasks[3].target_m[2]=1.0,1.2,1.4'
    """
    from casadi_posture.output.axes import axis_value
    from casadi_posture.runs.whatif import parse_vary

    parsed = [parse_vary(text, problem, unique=not paired) for text in varies]
    keys = [key for axis, _ in parsed for key in axis.split(",")]
    if len(set(keys)) != len(keys):
        raise ProblemError(problem, "--vary", keys, "each key varied once")
    out = out or Path("out", "whatif", Path(problem).stem)
    report = api.whatif(
        problem,
        dict(parsed),
        out,
        static=static,
        paired=paired,
        solver=solver,
        jobs=jobs,
        scheduler=scheduler,
        resume=resume,
        force=force,
        max_cases=max_cases,
        overrides=parse_sets(sets, problem),
        report=not no_report,
        quiet=quiet,
    )
    keys = [axis for axis, _ in parsed]
    headers = [*keys, "reached", "limiting group at start", "region", "endurance at start (min)"]
    headers += ["capable men (%)", "capable women (%)"]
    scheduled = not static and any(row.get("work_cycles") is not None for row in report.rows)
    if not static:
        headers += ["first at threshold (s)", "exhausted group", "cycles", "task held (s)"]
    if scheduled:
        headers.append("work cycles (held whole)")
    # The plausibility columns a task calls for: left/right apart on a symmetric task, out
    # of the plane on a sagittal one (the largest over a run's key postures).
    plausible = {
        key: header
        for key, header in (
            ("asymmetry_deg" if static else "max_asymmetry_deg", "left/right apart (deg)"),
            ("out_of_plane_deg" if static else "max_out_of_plane_deg", "out of plane (deg)"),
        )
        if any(row.get(key) is not None for row in report.rows)
    }
    headers += list(plausible.values())
    scored = any(row.get("worst_rula") is not None for row in report.rows)
    if scored:
        headers += ["worst RULA (level)", "worst REBA (risk)"]
    backs = any(row.get("peak_compression_N") is not None for row in report.rows)
    if backs:
        headers.append(f"{'' if static else 'peak '}L5/S1 compression (N)")
    headers.append("flags")
    order = {k: [str(v) for v in values] for k, values in parsed}

    def position(row: dict[str, Any]) -> list[int]:
        given = [str(axis_value(row, k)) for k in keys]
        return [
            order[k].index(v) if v in order[k] else -1 for k, v in zip(keys, given, strict=True)
        ]

    rows = []
    for row in sorted(report.rows, key=position):
        line = [axis_value(row, k) for k in keys]
        if row["status"] in ("failed", "skipped"):
            reason = f"{row['status']}: {row['error']}"
            rows.append(line + [None] * (len(headers) - len(line) - 1) + [reason])
            continue
        line += [
            _yes_no(row.get("reached")),
            row["limiting_group_at_start"] or "none",
            row["limiting_region_at_start"] or "-",
            _unlimited(row["limiting_endurance_at_start_min"]),
            row["capable_male_pct"],
            row["capable_female_pct"],
        ]
        if not static:
            line += [
                row["first_fatigue_s"],
                row["exhausted_group"] or "none",
                row["fatigue_recovery_cycles"],
                _held(row),
            ]
        if scheduled:
            line.append(_work_cycles(row))
        line += [row.get(key) for key in plausible]
        if scored:
            line += _scores(row)
        if backs:
            back = row.get("peak_compression_N")
            line.append(None if back is None else round(back))
        rows.append([*line, row["flags"] or "-"])
    right = {headers.index(h) for h in ("task held (s)",) if h in headers}
    if not {"fatigue.recovery_law", "fatigue.load_threshold_pct_mvc"} & set(keys):
        click.echo(f"recovery law: {law(load_problem(problem, parse_sets(sets, problem)))}\n")
    click.echo(table(headers, rows, digits=2, right=right))
    for row in sorted(report.rows, key=position):
        if row.get("notes"):
            click.echo(f"note: case {row['case']}: {row['notes']}")
    click.echo(f"\ntable: {out / 'whatif.csv'}; figures: {len(report.figures)} in {out}")
    _finish(report)


def _work_cycles(row: dict[str, Any]) -> str:
    """``13 (12)``: the work cycles a scheduled case began, and those held to their end."""
    if row.get("work_cycles") is None:
        return "-"
    return f"{row['work_cycles']} ({row['work_cycles_completed']})"


def _scores(row: dict[str, Any]) -> list[str]:
    """``5 (3)`` and ``4 (medium)``: the worst RULA with its action level, the worst REBA
    with its risk level."""
    if row.get("worst_rula") is None:
        return ["-", "-"]
    return [
        f"{row['worst_rula']} ({row['worst_rula_action_level']})",
        f"{row['worst_reba']} ({row['worst_reba_risk']})",
    ]


def _yes_no(value: Any) -> str:
    return "-" if value is None else ("yes" if value else "NO")


def _unlimited(minutes: float | None) -> float:
    """The limiting endurance: none when no group tires."""
    return math.inf if minutes is None else minutes


def _held(row: dict[str, Any]) -> str:
    """How long the task was held; '≥' when the run ended with it still held."""
    return f"{'≥ ' if row['task_held_is_lower_bound'] else ''}{row['task_held_s']:.2f}"
