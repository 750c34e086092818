"""The command group, its error handling, and helpers the commands share."""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from casadi_posture import __version__, interrupt
from casadi_posture.errors import CasadiPostureError, ProblemError
from casadi_posture.ik.solvers import SOLVER_NAMES
from casadi_posture.output.plain import dumps
from casadi_posture.output.report import DOF_COLUMNS, HALF_JOINT_COLUMNS, table
from casadi_posture.problem import Problem, load_problem
from casadi_posture.spec.overrides import parse_value, split_assignment
from casadi_posture.static import SCHEDULE_NOTE, StaticAnswer

INTERRUPTED = interrupt.EXIT_CODE

#: Set this environment variable to see the traceback of an internal error.
DEBUG = "CASADI_POSTURE_DEBUG"


class _Commands(click.Group):
    """A group that turns every input error into one line on stderr and exit code 2, and
    Ctrl-C into one line and exit code 130 (click alone says "Aborted!" and exits 1)."""

    def invoke(self, ctx: click.Context) -> Any:
        words = [*getattr(ctx, "_protected_args", []), *ctx.args]
        ctx.meta["command_line"] = ["casadi-posture", *words]
        try:
            return super().invoke(ctx)
        except (click.exceptions.Exit, click.exceptions.Abort, click.ClickException) as done:
            if not isinstance(done, click.UsageError):
                raise
            click.echo(f"error: {_usage(done, words)}", err=True)
            ctx.exit(2)
        except ProblemError as error:
            click.echo(f"error: {error}", err=True)
            ctx.exit(2)
        except CasadiPostureError as error:
            click.echo(f"failed: {error}", err=True)
            ctx.exit(1)
        except KeyboardInterrupt:
            click.echo("interrupted", err=True)
            ctx.exit(INTERRUPTED)
        except BrokenPipeError:  # the reader left (`... | head`): stop quietly, as Python advises
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            ctx.exit(1)
        except Exception as error:  # a bug: one line for the user, the traceback on request
            if isinstance(error, OSError) and error.filename is not None:
                # the file system refused a path after the checks before the run (a disk
                # that filled up, a folder removed meanwhile): the path and its reason
                click.echo(f"error: {error.filename}: {error.strerror}", err=True)
                ctx.exit(2)
            if os.environ.get(DEBUG):
                raise
            first = (str(error).splitlines() or [""])[0]
            click.echo(
                f"internal error: {type(error).__name__}: {first} (a bug: please report it "
                f"with the command line; {DEBUG}=1 shows the traceback)",
                err=True,
            )
            ctx.exit(1)


def _usage(error: click.UsageError, words: list[str]) -> str:
    """A command-line mistake in one line naming the problem file it concerns, if any."""
    files = [w for w in words[1:] if not w.startswith("-") and w.endswith(".toml")]
    where = f"{files[0]}: " if files else ""
    command = error.ctx.command_path if error.ctx is not None else "casadi-posture"
    return f"{where}{error.format_message()} (see {command} -h)"


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="casadi-posture")
def main() -> None:
    """Predict how a posture changes as the muscles tire (Rodriguez & Boulic 2008).

    Angles are in degrees, torques in N·m, lengths in m, times in s or min as
    each column header says. Bad input exits with code 2 and one line on stderr.

    Endurance by default: Manenica's, the paper's model, on the paper's planar arms (for
    fidelity to the paper, not accuracy: 36-80 % long at the shoulder between 30 and 70
    %MVC); Frey-Law & Avin's 2010 meta-analysis per joint region on the 3-D bodies.
    fatigue.endurance chooses another (docs/endurance.md).
    """


SOLVER_OPTION = click.option(
    "--solver",
    type=click.Choice(SOLVER_NAMES),
    default=None,
    help="IK solver [default: the file's solver.name].",
)


def parse_sets(items: tuple[str, ...], path: str | None = None) -> dict[str, Any]:
    """``--set KEY=VALUE`` options as dotted-key overrides, values read as TOML reads them
    (``5``, ``2.5``, ``"passive"`` or ``passive``, ``[0, 1]``)."""
    out: dict[str, Any] = {}
    for item in items:
        example = "KEY=VALUE such as fatigue.strategy=passive"
        key, value = split_assignment(item, "--set", path, example)
        out[key] = parse_value(value, path, f"--set {key}")
    return out


def problem_from(
    path: str,
    postures: tuple[str, ...] = (),
    overrides: dict[str, Any] | None = None,
    sets: tuple[str, ...] = (),
) -> Problem:
    """The problem file with ``--set`` overrides (then the command's own ones) and
    ``--posture`` angles applied, validated like the file; its notes printed."""
    problem = load_problem(path, parse_sets(sets, path) | (overrides or {}))
    if postures:
        problem = problem.with_posture(parse_postures(postures, path))
    echo_notes(problem)
    return problem


def echo_notes(problem: Problem) -> None:
    """The slips a problem may hold (spec/slips.py) as ``note:`` lines: on stdout, or on
    stderr under ``--json``, whose stdout is the JSON alone (which carries them too)."""
    context = click.get_current_context(silent=True)
    as_json = context is not None and bool(context.params.get("as_json"))
    for note in problem.notes:
        click.echo(f"note: {note}", err=as_json)


def parse_postures(items: tuple[str, ...], path: str | None = None) -> dict[str, float]:
    """``NAME=DEG`` options as {name: degrees}; ``path`` names the problem in errors."""
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            angle = float(value) if sep else math.nan
        except ValueError:
            angle = math.nan
        if not name or not math.isfinite(angle):
            raise ProblemError(path, "--posture", item, "NAME=DEG with DEG a number of degrees")
        out[name] = angle
    return out


def emit_json(data: Any) -> None:
    click.echo(dumps(data))


#: Half-joints a console table shows without --all: the most loaded ones.
SHOWN_GROUPS = 10

#: The --all flag of the commands that print a half-joint table.
ALL_OPTION = click.option(
    "--all",
    "show_all",
    is_flag=True,
    help=f"Print every DOF and half-joint [default: the {SHOWN_GROUPS} most loaded half-joints "
    "and their DOFs, on a body with more].",
)


def shown_groups(loads: Sequence[float], over: Sequence[bool], show_all: bool) -> list[int]:
    """Indices of the half-joints a table shows: every one with ``show_all`` or on a body of
    at most ``SHOWN_GROUPS``, else the most loaded [%MVC] (every one over strength among
    them), in the body's order."""
    order = sorted(range(len(loads)), key=lambda k: (not over[k], -loads[k]))
    if show_all or len(loads) <= SHOWN_GROUPS:
        return list(range(len(loads)))
    keep = order[:SHOWN_GROUPS] + [k for k in order[SHOWN_GROUPS:] if over[k]]
    return sorted(keep)


def echo_torques(answer: StaticAnswer, show_all: bool = False) -> None:
    """The DOF table and the half-joint table of a static answer (on a large body the most
    loaded half-joints and their DOFs, unless ``show_all``), and its endurance rule."""
    groups, capable = answer.groups, answer.capable.groups
    loads = [g.load_pct_mvc for g in groups]
    keep = shown_groups(loads, [g.over_strength for g in groups], show_all)
    dofs = answer.dofs()
    names = {groups[k].dof for k in keep}
    shown_dofs = [d for d in dofs if len(keep) == len(groups) or d["name"] in names]
    click.echo(
        table(
            DOF_COLUMNS,
            [list(d.values()) for d in shown_dofs],
        )
    )
    click.echo()
    click.echo(
        table(
            [*HALF_JOINT_COLUMNS, "capable men (%)", "capable women (%)"],
            [
                [
                    groups[k].name,
                    groups[k].dof,
                    groups[k].strength,
                    groups[k].torque,
                    groups[k].load_pct_mvc,
                    groups[k].endurance_min,
                    groups[k].verdict.upper() if groups[k].over_strength else groups[k].verdict,
                    capable[k].capable_pct["male"],
                    capable[k].capable_pct["female"],
                ]
                for k in keep
            ],
            digits=2,
        )
    )
    hidden = [k for k in range(len(groups)) if k not in keep]
    if hidden:
        most = max(loads[k] for k in hidden)
        click.echo(
            f"... {len(hidden)} more half-joints ({len(dofs) - len(shown_dofs)} more DOFs) "
            f"carry at most {most:.1f} %MVC; --all prints every row"
        )
    click.echo(f"\nendurance rule: {answer.rule}")
    click.echo(answer.capable.task_line())
    click.echo(answer.capable.sd_line())
    for note in answer.capable.notes():
        click.echo(f"note: {note}")
    if answer.problem.spec.schedule is not None:
        click.echo(f"note: {SCHEDULE_NOTE}")
    if answer.plausibility is not None:
        click.echo(f"plausibility of the {answer.plausibility.line()}")


def echo_free_dofs(problem: Problem) -> None:
    """A note when the tasks leave DOFs undetermined at the problem's posture."""
    if not problem.spec.tasks:
        return
    free = problem.hierarchy().free_dofs(problem.posture)
    if free:
        click.echo(
            f"note: the tasks leave {free} of {problem.body.n} DOFs free at the start; each "
            "solver settles them its own way unless a posture task at the lowest priority does"
        )


def command_line() -> list[str]:
    """The command line that started this command, for manifests."""
    return list(click.get_current_context().meta.get("command_line", []))


SET_OPTION = click.option(
    "--set",
    "sets",
    multiple=True,
    metavar="KEY=VALUE",
    help="Set a problem key before validation (repeatable): fatigue.strategy=passive, "
    "'loads[0].mass_kg=5' (quoted: shells read [0] as a pattern).",
)


def no_report_option(page: str):
    """The ``--no-report`` flag of a command whose report.html shows ``page``."""
    return click.option(
        "--no-report", "no_report", is_flag=True, help=f"Do not write report.html ({page})."
    )


def out_option(default: str) -> Any:
    """``--out DIR``, the output folder; ``default`` says where it goes without it."""
    return click.option(
        "--out",
        type=click.Path(file_okay=False, path_type=Path),
        default=None,
        help=f"Output folder [default: {default}].",
    )


FORCE_OPTION = click.option(
    "--force", is_flag=True, help="Overwrite the output if it exists (otherwise refused)."
)


#: This machine's cores: the processes a population runs on unless ``--jobs`` says otherwise.
CORES = os.cpu_count() or 1


def _jobs_option(every_core: bool) -> Any:
    return click.option(
        "--jobs",
        type=click.IntRange(min=1),
        default=CORES if every_core else 1,
        show_default=not every_core,
        help="Cases run in parallel on this machine"
        + (f" [default: every core, {CORES} here]." if every_core else "."),
    )


BATCH_OPTIONS = [
    click.option(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="Run on a Dask cluster, e.g. tcp://10.0.0.5:8786.",
    ),
    click.option(
        "--resume",
        is_flag=True,
        help="Continue the run in --out: finished cases are kept, failed ones run again.",
    ),
    click.option(
        "--force", is_flag=True, help="Start over: delete earlier results in --out first."
    ),
    click.option("--quiet", is_flag=True, help="No progress bar."),
]


def batch_options(command: Any = None, *, every_core: bool = False) -> Any:
    """``--jobs`` (one process by default; ``every_core``: one per core), ``--scheduler``,
    ``--resume``, ``--force`` and ``--quiet``; a decorator, or with ``every_core`` a
    decorator factory."""
    if command is None:
        return lambda decorated: batch_options(decorated, every_core=every_core)
    for option in reversed([_jobs_option(every_core), *BATCH_OPTIONS]):
        command = option(command)
    return command
