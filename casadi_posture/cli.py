"""The ``casadi-posture`` command line."""

from __future__ import annotations

import csv
import json
import math
import shutil
import sys
from pathlib import Path
from typing import Any

import click
import numpy as np

from . import __version__
from .compare import compare, rows
from .curve import torque_curve
from .describe import description
from .endurance import endurance_model
from .errors import CasadiPostureError, ProblemError
from .problem import Problem, load_problem
from .report import table
from .solvers import SOLVER_NAMES, make_solver


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


_SOLVER_OPTION = click.option(
    "--solver",
    type=click.Choice(SOLVER_NAMES),
    default=None,
    help="IK solver [default: the file's solver.name].",
)


def _problem(
    path: str, postures: tuple[str, ...] = (), overrides: dict[str, Any] | None = None
) -> Problem:
    problem = load_problem(path, overrides)
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
    dofs, groups = _torque_breakdown(resolved, resolved.posture)
    model_name = resolved.spec.fatigue.endurance
    if as_json:
        _emit_json(
            {
                "problem": problem,
                "endurance_model": model_name,
                "dofs": dofs,
                "half_joints": _json_groups(groups),
            }
        )
        return
    click.echo(f"{problem} ({resolved.body.name}); endurance model: {model_name}\n")
    _echo_torques(dofs, groups)


def _torque_breakdown(problem: Problem, q: np.ndarray) -> tuple[list[dict], list[dict]]:
    """Per DOF the torques [N·m] and per half-joint its strength, load and endurance at ``q``."""
    result = problem.torque_model().evaluate(q)
    endurance = endurance_model(problem.spec.fatigue.endurance)
    body = problem.body
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
    return dofs, groups


def _json_groups(groups: list[dict]) -> list[dict]:
    """Half-joint rows for JSON: an unlimited endurance is null."""
    return [
        {**g, "endurance_min": None if math.isinf(g["endurance_min"]) else g["endurance_min"]}
        for g in groups
    ]


def _echo_torques(dofs: list[dict], groups: list[dict]) -> None:
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
@_SOLVER_OPTION
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
    resolved = _problem(problem)
    hierarchy = resolved.hierarchy()
    name = solver or resolved.spec.solver.name
    result = make_solver(name, hierarchy, resolved.spec.solver).solve(resolved.posture)
    dofs, groups = _torque_breakdown(resolved, result.q)
    levels = [
        {"level": k + 1, "tasks": tasks, "residual": float(result.residuals[k]), "unit": unit}
        for k, (tasks, unit) in enumerate(
            zip(hierarchy.level_names(), hierarchy.level_units(), strict=True)
        )
    ]
    if as_json:
        _emit_json(
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
                "torques": {"dofs": dofs, "half_joints": _json_groups(groups)},
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
        _echo_torques(dofs, groups)
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
        resolved = _problem(path)
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


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@_SOLVER_OPTION
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
@click.option("--duration", type=float, default=None, help="Simulated time in s.")
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Output folder [default: out/simulate/<problem>-<strategy>-<solver>].",
)
def simulate(
    problem: str,
    solver: str | None,
    strategy: str | None,
    r_min: float | None,
    duration: float | None,
    out: Path | None,
) -> None:
    """Simulate holding the tasks over time: fatigue, the fatigue-reducing constraint with
    its hysteresis, recovery. Writes timeline.csv, events.csv, summary.json,
    manifest.json and figures into the output folder.

    \b
    Example:
      casadi-posture simulate problems/holding_m45.toml --strategy passive
      casadi-posture simulate problems/line_plane_hysteresis.toml --solver nullspace \\
          --duration 600 --out out/hysteresis
    """
    from .plots import plot_simulation
    from .results import summary, write_results
    from .simulation import simulate as run

    given = (
        ("fatigue.strategy", strategy),
        ("fatigue.r_min", r_min),
        ("simulation.duration_s", duration),
    )
    overrides = {key: value for key, value in given if value is not None}
    resolved = _problem(problem, overrides=overrides)
    result = run(resolved, solver)
    out = out or Path(
        "out", "simulate", f"{Path(problem).stem}-{result.settings.strategy}-{result.solver}"
    )
    files = write_results(result, out) + plot_simulation(result, out)
    report = summary(result)
    stats = report["solver_statistics"]
    click.echo(
        f"{problem}: {report['simulated_s']:.0f} s simulated, {result.solver} solver, "
        f"{report['strategy']} strategy; {stats['wall_time_s']:.2f} s wall, "
        f"{100 * (1 - stats['share_outside_ik']):.0f} % in IK, "
        f"{stats['ik_failures']} IK failures\n"
    )
    click.echo(
        table(
            [
                "half-joint",
                "initial load (%MVC)",
                "initial endurance (min)",
                "first at fatigue threshold (s)",
                "max fatigue",
            ],
            [
                [
                    g["half_joint"],
                    g["initial_load_pct_mvc"],
                    g["initial_endurance_min"],
                    g["first_fatigue_threshold_s"],
                    g["max_fatigue"],
                ]
                for g in report["half_joints"]
            ],
            digits=2,
        )
    )
    first = report["first_to_fatigue"]
    click.echo(
        f"\nfirst to fatigue: {first['half_joint']} at {first['time_s']:.0f} s"
        if first
        else "\nfirst to fatigue: none"
    )
    click.echo(f"fatigue/recovery cycles: {report['fatigue_recovery_cycles']}")
    for rec in report["recovery_postures"]:
        posture = ", ".join(f"{k} {v:.1f}°" for k, v in rec["posture_deg"].items())
        click.echo(f"  recovered at {rec['time_s']:.0f} s: {posture}")
    lost = report["task_lost"]
    click.echo(
        f"task could no longer be held at {lost['time_s']:.0f} s ({lost['half_joint']} exhausted)"
        if lost
        else "task held to the end"
    )
    click.echo("files: " + ", ".join(str(f) for f in files))


_BATCH_OPTIONS = [
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


def _batch_options(command: Any) -> Any:
    for option in reversed(_BATCH_OPTIONS):
        command = option(command)
    return command


@main.command()
@click.argument("problems", nargs=-1, required=True, type=click.Path())
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    required=True,
    help="Output folder: cases/<case>/ and summary.csv.",
)
@_SOLVER_OPTION
@_batch_options
def batch(
    problems: tuple[str, ...],
    out: Path,
    solver: str | None,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    quiet: bool,
) -> None:
    """Simulate many problem files (folders give their *.toml): each case in its own
    folder as simulate writes it, and one summary row per case in summary.csv (and
    summary.parquet when pyarrow is installed).

    A failing case is recorded with its reason and the batch carries on. Exit code 0
    when every case succeeded, 1 when some failed, 2 for usage errors. A killed batch
    rerun with --resume redoes no finished case.

    \b
    Example:
      casadi-posture batch problems/ --out out/batch --jobs 2
      casadi-posture batch problems/ --out out/batch --jobs 2 --resume
    """
    from .batch import cases_from_paths, run_batch

    report = run_batch(
        cases_from_paths(problems, solver),
        out,
        jobs=jobs,
        scheduler=scheduler,
        resume=resume,
        quiet=quiet,
    )
    click.echo(
        f"{len(report.rows)} cases ({report.ran} run now, {report.skipped} already "
        f"done), {len(report.failed)} failed; summary: {report.summary}"
    )
    for row in report.failed:
        click.echo(f"failed {row['case']}: {row['error']}")
    if report.failed:
        raise SystemExit(1)


@main.command()
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--vary",
    "varies",
    multiple=True,
    required=True,
    metavar="KEY=V1,V2,...",
    help="A problem key and its values (repeatable): loads[0].mass_kg=2.5,5, "
    "fatigue.strategy=active,passive, body.sex=male,female, solver=...",
)
@click.option(
    "--out",
    type=click.Path(file_okay=False, path_type=Path),
    default=None,
    help="Output folder [default: out/whatif/<problem>].",
)
@click.option(
    "--static", is_flag=True, help="Answer from torques at the start posture only (no time loop)."
)
@_SOLVER_OPTION
@_batch_options
def whatif(
    problem: str,
    varies: tuple[str, ...],
    out: Path | None,
    static: bool,
    solver: str | None,
    jobs: int,
    scheduler: str | None,
    resume: bool,
    quiet: bool,
) -> None:
    """What if the load, the line, the strategy, R_min, the thresholds, the body or the
    solver were different? Runs the grid of the varied keys and reports per case the
    endurance of each half-joint and of the task, the limiting muscle group, the
    fatigue/recovery cycles and the recovery posture: a table, whatif.csv and a plot
    of each outcome against each varied key.

    \b
    Example:
      casadi-posture whatif problems/holding_m45.toml --vary loads[0].mass_kg=1,2.5,5
      casadi-posture whatif problems/holding_m25.toml --vary tasks[0].elevation_deg=0,-25,-45 \\
          --vary fatigue.strategy=active,passive --jobs 2
      casadi-posture whatif problems/holding_m45.toml --vary body.mass_kg=60,73,90 --static
    """
    from .batch import run_batch
    from .whatif import grid, parse_vary, plot_outcomes

    parsed = [parse_vary(text) for text in varies]
    out = out or Path("out", "whatif", Path(problem).stem)
    cases = grid(problem, parsed, solver=solver, simulate=not static)
    report = run_batch(cases, out, jobs=jobs, scheduler=scheduler, resume=resume, quiet=quiet)
    shutil.copyfile(report.summary, out / "whatif.csv")
    keys = [k for k, _ in parsed]
    headers = [*keys, "limiting group", "endurance at start (min)"]
    if not static:
        headers += ["first at threshold (s)", "cycles", "task held (s)"]
    rows = []
    order = {k: [str(v) for v in values] for k, values in parsed}

    def position(row: dict[str, Any]) -> list[int]:
        given = [str(row.get("solver") if k == "solver" else row.get(k)) for k in keys]
        return [
            order[k].index(v) if v in order[k] else -1 for k, v in zip(keys, given, strict=True)
        ]

    for row in sorted(report.rows, key=position):
        if row["status"] != "ok":
            failed = [*(row.get(k) for k in keys), f"failed: {row['error']}"]
            rows.append(failed + [None] * (len(headers) - len(failed)))
            continue
        line = [
            *(row.get("solver") if k == "solver" else row.get(k) for k in keys),
            row["limiting_group"],
            row["limiting_endurance_min"],
        ]
        if not static:
            line += [row["first_fatigue_s"], row["fatigue_recovery_cycles"], row["task_held_s"]]
        rows.append(line)
    click.echo(table(headers, rows, digits=2))
    figures = plot_outcomes(report.rows, parsed, out, simulate=not static)
    click.echo(f"\ntable: {out / 'whatif.csv'}; figures: {len(figures)} in {out}")
    if report.failed:
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
