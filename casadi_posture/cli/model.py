"""Commands on the model and its torques: init, validate, describe, torques, curve."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click
import numpy as np
from click.shell_completion import CompletionItem

from casadi_posture import api
from casadi_posture.cli.common import (
    ALL_OPTION,
    FORCE_OPTION,
    SET_OPTION,
    echo_torques,
    emit_json,
    main,
    problem_from,
)
from casadi_posture.data.templates import TEMPLATES, template
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.output import low_back
from casadi_posture.output.report import table
from casadi_posture.output.scores import lines, static_report


def _templates_or_files(
    ctx: click.Context, param: click.Parameter, incomplete: str
) -> list[CompletionItem]:
    """Shell completion of init's first argument: the template names, then files."""
    names = [CompletionItem(name) for name in TEMPLATES if name.startswith(incomplete)]
    return [*names, CompletionItem(incomplete, type="file")]


@main.command()
@click.argument("template_or_file", shell_complete=_templates_or_files)
@click.argument("file", required=False, type=click.Path(dir_okay=False, path_type=Path))
@FORCE_OPTION
def init(template_or_file: str, file: Path | None, force: bool) -> None:
    """Write a commented problem file to start from: TEMPLATE is hold (the default: a load
    held with the wrist on a line, the paper's experiment), elbow (only the elbow moves,
    the paper's Fig. 3), tree (a 3-DOF arm described in the file: a body of your own),
    shelf (a standing person, a box in both hands at a shelf) or seated (a seated person,
    a part on a table). Every key is explained in the file.

    \b
    Example:
      casadi-posture init my_hold.toml
      casadi-posture init elbow my_elbow.toml
      casadi-posture init tree my_arm.toml
      casadi-posture init shelf my_shelf.toml
      casadi-posture init seated my_bench.toml
    """
    if file is None and template_or_file in TEMPLATES:
        raise ProblemError(None, "FILE", MISSING, f"the file to write after {template_or_file}")
    name, target = (template_or_file, file) if file else ("hold", Path(template_or_file))
    if name not in TEMPLATES:
        raise ProblemError(None, "TEMPLATE", name, f"one of {sorted(TEMPLATES)}")
    api.check_out(target, force=force, key="FILE", folder=False)
    if not target.parent.is_dir():
        raise ProblemError(None, "FILE", str(target), "a file in an existing folder")
    target.write_text(template(name), encoding="utf-8")
    click.echo(f"written: {target} (from the {name} template; check it with validate)")


@main.command()
@click.argument("problems", nargs=-1, required=True, type=click.Path())
@SET_OPTION
def validate(problems: tuple[str, ...], sets: tuple[str, ...]) -> None:
    """Check problem files (folders give their *.toml); print 'ok' per valid file and one
    error line per invalid one, and exit with code 2 if any is invalid.

    \b
    Example:
      casadi-posture validate problems/
    """
    paths = [
        str(f)
        for p in map(Path, problems)
        for f in (sorted(p.glob("*.toml")) if p.is_dir() else [p])
    ]
    if not paths:
        raise ProblemError(problems[0], None, None, "a folder with .toml files")
    invalid = 0
    for path in paths:
        try:
            problem = problem_from(path, sets=sets)
        except ProblemError as error:
            click.echo(f"error: {error}", err=True)
            invalid += 1
            continue
        click.echo(
            f"ok  {path}  ({problem.body.name}, {problem.body.n} DOF, "
            f"{len(problem.loads)} loads, {len(problem.tasks)} tasks)"
        )
    if invalid:
        raise SystemExit(2)


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@SET_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def describe(problem: str, sets: tuple[str, ...], as_json: bool) -> None:
    """Show the resolved model: DOFs, segments, loads, tasks, parameters and their sources.

    Positions are world coordinates at the zero posture (x forward, y left, z up).

    \b
    Example:
      casadi-posture describe problems/holding_m45.toml
      casadi-posture describe problems/holding_m45.toml --json > model.json
    """
    data = api.describe(problem_from(problem, sets=sets))
    if as_json:
        emit_json(data)
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
                    d.get("parent", "world"),
                    _vec(d["origin_m"]),
                    _vec(d["axis"], 3),
                    f"[{d['range_deg'][0]:g}, {d['range_deg'][1]:g}]",
                    f"{d['positive']['name']} / {d['negative']['name']}",
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
                [s["name"], s["mass_kg"], _vec(s["com_m"]), s.get("dof", "(fixed)")]
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
@SET_OPTION
@ALL_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def torques(
    problem: str, postures: tuple[str, ...], sets: tuple[str, ...], show_all: bool, as_json: bool
) -> None:
    """Per DOF the external, passive and active torque; per half-joint its load, endurance
    and a verdict: carries nothing, unlimited (the fatigue model accumulates nothing at
    this load), limited, or over strength (above 100 %MVC: endurance 0, the posture cannot
    be held; the command then exits with code 1).

    \b
    Example:
      casadi-posture torques problems/holding_m45.toml
      casadi-posture torques problems/holding_m45.toml --posture shoulder_flexion=90 \\
          --posture elbow_flexion=0 --json
    """
    resolved = problem_from(problem, postures, sets=sets)
    answer = api.torques(resolved)
    if as_json:
        emit_json(
            {
                "problem": problem,
                "endurance_model": resolved.fatigue.endurance_model,
                "recovery_law": resolved.fatigue.name,
                "endurance_rule": answer.rule,
                "feasible": answer.feasible,
                "flags": list(answer.flags),
                "notes": list(answer.problem.notes),
                "dofs": answer.dofs(),
                "half_joints": answer.half_joints(),
                "capable": answer.capable_report(),
                "plausibility": answer.plausibility.to_dict() if answer.plausibility else None,
                "rula_reba": static_report(answer.problem, answer.scores),
                "low_back": low_back.static_report(answer.low_back),
            }
        )
    else:
        click.echo(f"{problem} ({resolved.body.name})\n")
        echo_torques(answer, show_all)
        for line in [*lines(answer.problem, answer.scores), *low_back.lines(answer.low_back)]:
            click.echo(line)
        for flag in answer.flags:
            click.echo(f"FLAGGED: {flag}")
    if answer.flags:
        raise SystemExit(1)


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
    help="Figure to write: .png, .pdf, .svg, ... [default: <problem>-<dof>.png].",
)
@SET_OPTION
@FORCE_OPTION
def curve(
    problem: str,
    dof: str,
    postures: tuple[str, ...],
    out: Path | None,
    sets: tuple[str, ...],
    force: bool,
) -> None:
    """Plot τp, τe, τa and -τa over one DOF's range (the paper's Fig. 3) and print the
    angles where the active torque is zero.

    \b
    Example:
      casadi-posture curve problems/frontal_elbow.toml --dof elbow_flexion --out fig3.png
    """
    out = out or Path(f"{Path(problem).stem}-{dof}.png")
    api.check_figure(out, force=force, key="--out", source=problem)
    resolved = problem_from(problem, postures, sets=sets)
    if dof not in resolved.body.index:
        raise ProblemError(problem, "--dof", dof, f"one of {resolved.body.dof_names}")
    result = api.curve(resolved, dof)
    api.plot_curve(result, out, title=f"{Path(problem).stem}: torques over {dof}", force=True)
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
