"""The command group, its error handling, and helpers the commands share."""

from __future__ import annotations

import json
import math
from typing import Any

import click
import numpy as np

from .. import __version__
from ..endurance import endurance_model, half_joint_endurance_s
from ..errors import CasadiPostureError, ProblemError
from ..problem import Problem, load_problem
from ..report import table
from ..solvers import SOLVER_NAMES


class _Commands(click.Group):
    """A group that turns every library error into one line on stderr and exit code 2."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except CasadiPostureError as error:
            click.echo(f"error: {error}", err=True)
            ctx.exit(2)


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="casadi-posture")
def main() -> None:
    """Predict how a posture changes as the muscles tire (Rodriguez & Boulic 2008).

    Angles are in degrees, torques in N·m, lengths in m, times in s or min as
    each column header says. Bad input exits with code 2 and one line on stderr.
    """


SOLVER_OPTION = click.option(
    "--solver",
    type=click.Choice(SOLVER_NAMES),
    default=None,
    help="IK solver [default: the file's solver.name].",
)


def problem_from(
    path: str, postures: tuple[str, ...] = (), overrides: dict[str, Any] | None = None
) -> Problem:
    problem = load_problem(path, overrides)
    if postures:
        problem = problem.with_posture(parse_postures(postures))
    return problem


def parse_postures(items: tuple[str, ...]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            angle = float(value) if sep else math.nan
        except ValueError:
            angle = math.nan
        if not name or not math.isfinite(angle):
            raise ProblemError(None, "--posture", item, "NAME=DEG with DEG a number of degrees")
        out[name] = angle
    return out


def emit_json(data: Any) -> None:
    click.echo(json.dumps(data, indent=2, allow_nan=False))


def torque_breakdown(problem: Problem, q: np.ndarray) -> tuple[list[dict], list[dict]]:
    """Per DOF the torques [N·m] and per half-joint its strength, load and endurance at ``q``."""
    result = problem.torque_model().evaluate(q)
    endurance = endurance_model(problem.spec.fatigue.endurance)
    body = problem.body
    groups = []
    for k, half in enumerate(body.half_joints):
        load = float(result.load_pct_mvc[k])
        seconds = half_joint_endurance_s(endurance, load, half.region)
        groups.append(
            {
                "name": half.name,
                "dof": half.dof,
                "strength_Nm": float(result.strength[k]),
                "torque_Nm": float(result.half_joint_torque[k]),
                "load_pct_mvc": load,
                "endurance_min": seconds / 60.0,
            }
        )
    dofs = [
        {
            "name": d.name,
            "angle_deg": math.degrees(result.q[i]),
            "external_Nm": float(result.external[i]),
            "passive_Nm": float(result.passive[i]),
            "active_Nm": float(result.active[i]),
        }
        for i, d in enumerate(body.dofs)
    ]
    return dofs, groups


def json_groups(groups: list[dict]) -> list[dict]:
    """Half-joint rows for JSON: an unlimited endurance is null."""
    return [
        {**g, "endurance_min": None if math.isinf(g["endurance_min"]) else g["endurance_min"]}
        for g in groups
    ]


def echo_torques(dofs: list[dict], groups: list[dict]) -> None:
    click.echo(
        table(
            ["DOF", "angle (deg)", "external (N·m)", "passive (N·m)", "active (N·m)"],
            [list(d.values()) for d in dofs],
        )
    )
    click.echo()
    click.echo(
        table(
            [
                "half-joint",
                "DOF",
                "strength (N·m)",
                "torque (N·m)",
                "load (%MVC)",
                "endurance (min)",
            ],
            [list(g.values()) for g in groups],
            digits=2,
        )
    )


BATCH_OPTIONS = [
    click.option(
        "--jobs",
        type=click.IntRange(min=1),
        default=1,
        show_default=True,
        help="Cases run in parallel on this machine.",
    ),
    click.option(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="Run on a Dask cluster, e.g. tcp://10.0.0.5:8786.",
    ),
    click.option(
        "--resume",
        is_flag=True,
        help="Continue a batch in --out: finished cases are not run again.",
    ),
    click.option("--quiet", is_flag=True, help="No progress bar."),
]


def batch_options(command: Any) -> Any:
    for option in reversed(BATCH_OPTIONS):
        command = option(command)
    return command
