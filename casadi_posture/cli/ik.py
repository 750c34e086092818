"""Commands on the IK solvers: solve, compare."""

from __future__ import annotations

import csv
from pathlib import Path

import click

from ..compare import compare, rows
from ..report import table
from ..solvers import make_solver
from .common import (
    SOLVER_OPTION,
    echo_torques,
    emit_json,
    json_groups,
    main,
    problem_from,
    torque_breakdown,
)


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@SOLVER_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def solve(problem: str, solver: str | None, as_json: bool) -> None:
    """Solve the prioritized IK of a problem from its posture_deg; print the posture,
    the residual of each priority level, the active constraints and the torques there.

    Exits with code 1 when the solver fails (its status is printed).

    \b
    Example:
      casadi-posture solve problems/line_plane_hysteresis.toml
      casadi-posture solve problems/line_plane_hysteresis.toml --solver nullspace --json
    """
    resolved = problem_from(problem)
    hierarchy = resolved.hierarchy()
    name = solver or resolved.spec.solver.name
    result = make_solver(name, hierarchy, resolved.spec.solver).solve(resolved.posture)
    dofs, groups = torque_breakdown(resolved, result.q)
    levels = [
        {"level": k + 1, "tasks": tasks, "residual": float(result.residuals[k]), "unit": unit}
        for k, (tasks, unit) in enumerate(
            zip(hierarchy.level_names(), hierarchy.level_units(), strict=True)
        )
    ]
    if as_json:
        emit_json(
            {
                "problem": problem,
                "solver": name,
                "status": result.status,
                "success": result.success,
                "iterations": result.iterations,
                "wall_time_s": result.wall_time_s,
                "posture_deg": {d["name"]: d["angle_deg"] for d in dofs},
                "levels": levels,
                "at_limits": list(result.at_limits),
                "inequality_active": result.inequality_active,
                "torques": {"dofs": dofs, "half_joints": json_groups(groups)},
            }
        )
    else:
        click.echo(
            f"{problem}: {name}, status {result.status}, {result.iterations} iterations, "
            f"{1e3 * result.wall_time_s:.2f} ms\n"
        )
        click.echo(
            table(
                ["level", "tasks", "residual", "unit"],
                [[lv["level"], lv["tasks"], f"{lv['residual']:.3g}", lv["unit"]] for lv in levels],
            )
        )
        limits = ", ".join(result.at_limits) or "none"
        click.echo(f"\njoints at a limit: {limits}\n")
        echo_torques(dofs, groups)
    if not result.success:
        raise SystemExit(1)


@main.command(name="compare")
@click.argument("problems", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Folder for compare.csv.",
)
def compare_command(problems: tuple[str, ...], out: Path | None) -> None:
    """Solve each problem with both IK solvers from the same start and compare them:
    residual per level, largest joint difference, wall time, status, and a verdict
    that says why they disagree (an unreachable target, two posture families).

    Problems without tasks are skipped. Exits with code 1 when any problem disagrees.

    \b
    Example:
      casadi-posture compare problems/*.toml --out out/compare
    """
    table_rows: list[dict[str, object]] = []
    disagreements = 0
    for path in problems:
        resolved = problem_from(path)
        if not resolved.tasks:
            click.echo(f"skipped {path}: no tasks")
            continue
        comparison = compare(resolved)
        disagreements += not comparison.agree
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
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        with (out / "compare.csv").open("w", newline="", encoding="utf-8") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(table_rows[0]) if table_rows else [])
            writer.writeheader()
            writer.writerows(table_rows)
        click.echo(f"\nwritten: {out / 'compare.csv'}")
    if disagreements:
        raise SystemExit(1)
