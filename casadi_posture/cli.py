"""The ``casadi-posture`` command line."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import click
import numpy as np

from . import __version__
from .curve import torque_curve
from .describe import description
from .endurance import endurance_model
from .errors import CasadiPostureError, ProblemError
from .problem import Problem, load_problem
from .report import table


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


def _problem(path: str, postures: tuple[str, ...] = ()) -> Problem:
    problem = load_problem(path)
    if postures:
        problem = problem.with_posture(_parse_postures(postures))
    return problem


def _parse_postures(items: tuple[str, ...]) -> dict[str, float]:
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


def _emit_json(data: Any) -> None:
    click.echo(json.dumps(data, indent=2, allow_nan=False))


@main.command()
@click.argument("problems", nargs=-1, required=True, type=click.Path(dir_okay=False))
def validate(problems: tuple[str, ...]) -> None:
    """Check problem files; print 'ok' per valid file.

    \b
    Example:
      casadi-posture validate problems/*.toml
    """
    for path in problems:
        problem = load_problem(path)
        click.echo(
            f"ok  {path}  ({problem.body.name}, {problem.body.n} DOF, "
            f"{len(problem.loads)} loads, {len(problem.tasks)} tasks)"
        )


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def describe(problem: str, as_json: bool) -> None:
    """Show the resolved model: DOFs, segments, loads, tasks, parameters and their sources.

    Positions are world coordinates at the zero posture (x forward, y left, z up).

    \b
    Example:
      casadi-posture describe problems/holding_m45.toml
      casadi-posture describe problems/holding_m45.toml --json > model.json
    """
    data = description(_problem(problem))
    if as_json:
        _emit_json(data)
        return
    click.echo(f"{data['problem']}: {data['title']}")
    click.echo(
        f"model {data['model']}, {data['sex']}, stature {data['stature_m']} m, "
        f"body mass {data['body_mass_kg']} kg, g = {data['gravity_m_s2']} m/s²\n"
    )
    click.echo(
        table(
            ["DOF", "parent", "origin (m)", "axis", "range (deg)", "positive / negative group"],
            [
                [
                    d["name"],
                    d["parent"] or "world",
                    _vec(d["origin_m"]),
                    _vec(d["axis"], 3),
                    f"[{d['range_deg'][0]:g}, {d['range_deg'][1]:g}]",
                    f"{d['half_joints']['positive']} / {d['half_joints']['negative']}",
                ]
                for d in data["dofs"]
            ],
        )
    )
    click.echo()
    click.echo(
        table(
            ["segment", "mass (kg)", "COM (m)", "moved by DOF"],
            [
                [s["name"], s["mass_kg"], _vec(s["com_m"]), s["dof"] or "(fixed)"]
                for s in data["segments"]
            ],
        )
    )
    click.echo()
    if data["loads"]:
        click.echo(
            table(
                ["load", "at", "point (m)", "mass (kg)", "force (N)", "moved by DOF"],
                [
                    [
                        ld["name"],
                        ld["at"],
                        _vec(ld["point_m"]),
                        ld["mass_kg"],
                        _vec(ld["force_N"], 1),
                        ld["dof"] or "(fixed)",
                    ]
                    for ld in data["loads"]
                ],
            )
        )
        click.echo()
    if data["tasks"]:
        click.echo(
            table(
                ["task", "kind", "priority"],
                [[t["name"], t["kind"], t["priority"]] for t in data["tasks"]],
            )
        )
        click.echo()
    click.echo(
        table(
            ["parameter", "value", "unit", "status", "source"],
            [
                [p["name"], _value(p["value"]), p["unit"], p["status"], p["source"]]
                for p in data["parameters"]
            ],
        )
    )


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--posture",
    "postures",
    multiple=True,
    metavar="NAME=DEG",
    help="Set a DOF angle in degrees (repeatable); default: the file's posture_deg.",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def torques(problem: str, postures: tuple[str, ...], as_json: bool) -> None:
    """Per DOF the external, passive and active torque; per half-joint its load and endurance.

    \b
    Example:
      casadi-posture torques problems/holding_m45.toml
      casadi-posture torques problems/holding_m45.toml --posture shoulder_flexion=90 \\
          --posture elbow_flexion=0 --json
    """
    resolved = _problem(problem, postures)
    result = resolved.torque_model().evaluate(resolved.posture)
    model_name = resolved.spec.fatigue.endurance
    endurance = endurance_model(model_name)
    body = resolved.body
    groups = []
    for k, half in enumerate(body.half_joints):
        load = float(result.load_pct_mvc[k])
        seconds = (
            math.inf
            if result.half_joint_torque[k] == 0.0
            else float(endurance.endurance_time_s(load, half.region))
        )
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
    if as_json:
        for group in groups:
            if math.isinf(group["endurance_min"]):
                group["endurance_min"] = None
        _emit_json(
            {"problem": problem, "endurance_model": model_name, "dofs": dofs, "half_joints": groups}
        )
        return
    click.echo(f"{problem} ({body.name}); endurance model: {model_name}\n")
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


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("--dof", required=True, help="The DOF to sweep over its range.")
@click.option(
    "--posture",
    "postures",
    multiple=True,
    metavar="NAME=DEG",
    help="Hold another DOF at this angle in degrees (repeatable).",
)
@click.option(
    "--out",
    type=click.Path(dir_okay=False, path_type=Path),
    default=None,
    help="PNG file to write [default: <problem>-<dof>.png].",
)
def curve(problem: str, dof: str, postures: tuple[str, ...], out: Path | None) -> None:
    """Plot τp, τe, τa and -τa over one DOF's range (the paper's Fig. 3) and print the
    angles where the active torque is zero.

    \b
    Example:
      casadi-posture curve problems/frontal_elbow.toml --dof elbow_flexion --out fig3.png
    """
    from .plots import plot_torque_curve

    resolved = _problem(problem, postures)
    if dof not in resolved.body.index:
        raise ProblemError(None, "--dof", dof, f"one of {resolved.body.dof_names}")
    result = torque_curve(resolved.torque_model(), resolved.posture, dof)
    out = out or Path(f"{Path(problem).stem}-{dof}.png")
    plot_torque_curve(result, out, f"{Path(problem).stem}: torques over {dof}")
    click.echo(f"zeros of the active torque over {dof} (other DOFs held at the problem's posture):")
    click.echo(
        table(
            ["angle (deg)", "passive = -external (N·m)", "kind"],
            [[float(np.degrees(z.angle)), z.passive, z.kind] for z in result.zeros],
        )
    )
    click.echo(f"figure: {out}")


def _vec(values: list[float], digits: int = 4) -> str:
    return "(" + ", ".join(f"{v:.{digits}f}" for v in values) + ")"


def _value(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


if __name__ == "__main__":
    sys.exit(main())
