"""Commands on the IK solvers: solve, compare."""

from __future__ import annotations

import csv
from pathlib import Path

import click

from casadi_posture.cli.common import (
    SOLVER_OPTION,
    echo_torques,
    emit_json,
    json_groups,
    main,
    over_strength_message,
    problem_from,
    torque_breakdown,
)
from casadi_posture.ik.result import ACHIEVED_TOLERANCE, IKResult
from casadi_posture.ik.solvers import make_solver
from casadi_posture.output.report import table
from casadi_posture.runs.compare import compare, rows
from casadi_posture.static import GroupLoad, rule


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@SOLVER_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def solve(problem: str, solver: str | None, as_json: bool) -> None:
    """Solve the prioritized IK of a problem from its posture_deg; print the posture,
    the residual of each priority level and whether it was achieved, the active
    constraints and the torques there.

    Exits with code 1, saying why, when the answer cannot be used as it is: the solver
    failed (its status is printed), level 1 was not achieved (residual above
    0.0001 m or rad: out of reach, or blocked by a joint limit) or a muscle group would
    need more than its strength.

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
        {
            "level": k + 1,
            "tasks": tasks,
            "residual": float(result.residuals[k]),
            "unit": unit,
            "achieved": result.achieved[k],
        }
        for k, (tasks, unit) in enumerate(
            zip(hierarchy.level_names(), hierarchy.level_units(), strict=True)
        )
    ]
    flags = solve_flags(result, levels, groups)
    if as_json:
        emit_json(
            {
                "problem": problem,
                "solver": name,
                "status": result.status,
                "success": result.success,
                "reached": result.achieved[0],
                "flags": flags,
                "iterations": result.iterations,
                "wall_time_s": result.wall_time_s,
                "posture_deg": {d["name"]: d["angle_deg"] for d in dofs},
                "achieved_tolerance": ACHIEVED_TOLERANCE,
                "levels": levels,
                "at_limits": list(result.at_limits),
                "inequality_active": result.inequality_active,
                "endurance_rule": rule(resolved),
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
                ["level", "tasks", "residual", "unit", f"achieved (≤ {ACHIEVED_TOLERANCE:g})"],
                [
                    [
                        lv["level"],
                        lv["tasks"],
                        f"{lv['residual']:.3g}",
                        lv["unit"],
                        "yes" if lv["achieved"] else "NO",
                    ]
                    for lv in levels
                ],
            )
        )
        limits = ", ".join(result.at_limits) or "none"
        click.echo(f"\njoints at a limit: {limits}\n")
        echo_torques(resolved, dofs, groups)
        for flag in flags:
            click.echo(f"FLAGGED: {flag}")
    if flags:
        raise SystemExit(1)


def solve_flags(result: IKResult, levels: list[dict], groups: list[GroupLoad]) -> list[str]:
    """Why a solve's answer cannot be used as it is, one line each (empty: it can)."""
    flags = [] if result.success else [f"the {result.solver} solver failed: {result.status}"]
    top = levels[0]
    if not top["achieved"]:
        flags.append(
            f"level 1 ({top['tasks']}) not achieved: residual {top['residual']:.3g} "
            f"{top['unit']} > {ACHIEVED_TOLERANCE:g} {top['unit']}; the task is out of the "
            "body's reach or blocked by a joint limit (positions are in metres)"
        )
    over = over_strength_message(groups)
    return flags + ([over] if over else [])


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

    Problems without tasks are skipped. Exits with code 1 when any problem disagrees, a
    solver fails, or level 1 is not achieved (residual above 0.0001 m or rad).

    \b
    Example:
      casadi-posture compare problems/*.toml --out out/compare
    """
    table_rows: list[dict[str, object]] = []
    flagged = []
    for path in problems:
        resolved = problem_from(path)
        if not resolved.tasks:
            click.echo(f"skipped {path}: no tasks")
            continue
        comparison = compare(resolved)
        if not comparison.agree:
            flagged.append(f"{path}: the solvers disagree: {comparison.verdict}")
        unreached = [
            r.solver for r in (comparison.nullspace, comparison.lexicographic) if not r.achieved[0]
        ]
        if unreached:
            flagged.append(f"{path}: level 1 not achieved by {' and '.join(unreached)}")
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
    for line in flagged:
        click.echo(f"FLAGGED: {line}")
    if flagged:
        raise SystemExit(1)
