"""The sensitivity command: what matters most for a task's endurance, by AD."""

from __future__ import annotations

import csv
from pathlib import Path

import click

from casadi_posture import api
from casadi_posture.biomech.low_back import MODEL
from casadi_posture.cli.common import (
    FORCE_OPTION,
    SET_OPTION,
    SOLVER_OPTION,
    emit_json,
    main,
    problem_from,
)
from casadi_posture.output.plain import dumps
from casadi_posture.output.report import table
from casadi_posture.sensitivity_analysis.analysis import Sensitivity, sensitivity
from casadi_posture.sensitivity_analysis.parametric import KINDS


@main.command(name="sensitivity")
@click.argument("problem", type=click.Path(dir_okay=False))
@SOLVER_OPTION
@click.option(
    "--top",
    type=click.IntRange(min=1),
    default=15,
    show_default=True,
    help="Inputs shown in the table and the tornado plot (--json and --out: all).",
)
@click.option(
    "--kind",
    "kinds",
    multiple=True,
    type=click.Choice(KINDS),
    help="Rank only inputs of these kinds (repeatable) [default: all].",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Write sensitivity.json, sensitivity.csv and tornado.png into this folder.",
)
@SET_OPTION
@FORCE_OPTION
def sensitivity_command(
    problem: str,
    solver: str | None,
    top: int,
    kinds: tuple[str, ...],
    as_json: bool,
    out: Path | None,
    sets: tuple[str, ...],
    force: bool,
) -> None:
    """Rank every numeric input of a problem by how much it changes the task's static
    endurance: the derivatives of every group's start load and endurance and of the
    task's endurance with respect to load masses, forces and moments, task targets,
    stature, body mass and age, strengths, passive and endurance coefficients, at the
    posture the IK solves for, that posture's own change included (implicit function
    theorem). Elasticity = % change of the outcome per % change of the input.

    Exits with code 1 when the answer is flagged (level 1 not achieved, a group over
    its strength, derivatives that hold the posture fixed).

    \b
    Example:
      casadi-posture sensitivity problems/holding_horizontal.toml
      casadi-posture sensitivity problems/standing_wall_horizontal.toml --top 10 --out out/sens
    """
    resolved = problem_from(problem, sets=sets)
    if out is not None:
        api.check_out(out, force=force)
    result = sensitivity(resolved, solver)
    if as_json:
        emit_json(result.to_dict())
    else:
        _echo(result, problem, top, kinds)
    if out is not None:
        files = _write(result, out, top, kinds)
        if not as_json:
            click.echo("\nwrote: " + ", ".join(str(f) for f in files))
    if result.flags:
        raise SystemExit(1)


def _title(result: Sensitivity) -> str:
    if result.task_endurance_s is None and result.flags:
        return "the task's endurance is not differentiated: see the flags below"
    if result.task_endurance_s is None:
        return "no group tires: the task's endurance is unlimited"
    load = result.load_pct_mvc[result.groups.index(result.limiting)]
    return (
        f"task's static endurance {result.task_endurance_s / 60:.2f} min,\n"
        f"limited by {result.limiting} ({load:.1f} %MVC)"
    )


def _echo(result: Sensitivity, problem: str, top: int, kinds: tuple[str, ...]) -> None:
    posture = result.posture
    if not result.answer.problem.tasks:
        how = "the file's posture (no tasks)"
    elif posture.dq is not None:
        how = "posture derivative by the implicit function theorem"
    else:
        how = "posture held fixed"
    click.echo(
        f"{problem}: {len(result.inputs)} inputs, {how}\n{_title(result).replace(chr(10), ' ')}\n"
    )
    ranked = result.ranked(kinds)
    rows = ranked[:top]
    if rows:
        click.echo(
            table(
                [
                    "input",
                    "value",
                    "unit",
                    "d endurance (min per unit)",
                    "elasticity",
                    "d load (%MVC per unit)",
                ],
                [
                    [
                        r["key"],
                        r["value"],
                        r["unit"],
                        r["d_endurance_min_per_unit"],
                        _elasticity(r["endurance_elasticity"]),
                        r["d_load_pct_mvc_per_unit"],
                    ]
                    for r in rows
                ],
                digits=4,
            )
        )
        click.echo(
            f"\nelasticity: % change of the task's endurance per % change of the input; "
            f"{len(ranked) - len(rows)} more inputs ranked in --json / --out"
        )
    _echo_compression(result, top, kinds)
    for key, why in result.left_out.items():
        click.echo(f"note: {key} is not an input: {why}")
    for flag in result.flags:
        click.echo(f"FLAGGED: {flag}")


def _elasticity(value: float | None) -> float | str:
    """An elasticity for a table: none exists for an input whose value is 0."""
    return "n/a (input 0)" if value is None else value


def _echo_compression(result: Sensitivity, top: int, kinds: tuple[str, ...]) -> None:
    """The inputs ranked by the L5/S1 compression's elasticity (a body with a lumbar joint)."""
    ranked = result.ranked_compression(kinds)
    if result.compression is None or not ranked:
        return
    click.echo(f"\nlow-back compression at L5/S1 {result.compression:.0f} N, by the {MODEL}\n")
    click.echo(
        table(
            ["input", "value", "unit", "d compression (N per unit)", "elasticity"],
            [
                [
                    r["key"],
                    r["value"],
                    r["unit"],
                    r["d_compression_N_per_unit"],
                    _elasticity(r["compression_elasticity"]),
                ]
                for r in ranked[:top]
            ],
            digits=4,
        )
    )
    click.echo(
        "\nelasticity: % change of the compression per % change of the input; "
        f"{len(ranked) - min(top, len(ranked))} more inputs ranked in --json / --out"
    )


def _write(result: Sensitivity, out: Path, top: int, kinds: tuple[str, ...]) -> list[Path]:
    """sensitivity.json (everything), sensitivity.csv (the ranked inputs), tornado.png."""
    out.mkdir(parents=True, exist_ok=True)
    data, ranked, figure = out / "sensitivity.json", out / "sensitivity.csv", out / "tornado.png"
    data.write_text(dumps(result.to_dict()) + "\n", encoding="utf-8")
    rows = result.ranked(kinds)
    with ranked.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else ["key"])
        writer.writeheader()
        writer.writerows(rows)
    files = [data, ranked]
    if rows:
        from casadi_posture.output.tornado import plot_tornado  # imported when drawn

        files.append(plot_tornado(rows, _title(result), figure, top))
    return files
