"""A simulation's results as plain files: timeline.csv, events.csv, summary.json, manifest.json."""

from __future__ import annotations

import csv
import json
import math
import platform
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from . import __version__
from .describe import description
from .endurance import endurance_model, half_joint_endurance_s
from .simulation import SimulationResult


def summary(result: SimulationResult) -> dict[str, Any]:
    """Per half-joint endurance, the first to fatigue, cycles, recovery postures, whether and
    when the task could no longer be held, and solver statistics (times in s)."""
    tl, body = result.timeline, result.problem.body
    settings = result.settings
    model = endurance_model(result.problem.spec.fatigue.endurance)
    groups = []
    for k, half in enumerate(body.half_joints):
        first = np.flatnonzero(tl.fatigue[:, k] >= settings.fatigue_threshold)
        load0 = float(tl.load[0, k])
        initial = half_joint_endurance_s(model, load0, half.region)
        groups.append(
            {
                "half_joint": half.name,
                "dof": half.dof,
                "initial_load_pct_mvc": load0,
                "initial_endurance_min": None if math.isinf(initial) else initial / 60.0,
                "first_fatigue_threshold_s": float(tl.time[first[0]]) if first.size else None,
                "max_fatigue": float(tl.fatigue[:, k].max()),
                "final_fatigue": float(tl.fatigue[-1, k]),
            }
        )
    crossings = [e for e in result.events if e.kind == "fatigue_threshold"]
    lost = next((e for e in result.events if e.kind == "exhausted"), None)
    names = body.dof_names
    recoveries = []
    for event in (e for e in result.events if e.kind == "constraint_off"):
        step = int(np.searchsorted(tl.time, event.time_s))
        recoveries.append(
            {
                "time_s": event.time_s,
                "half_joint": event.half_joint,
                "posture_deg": dict(zip(names, np.degrees(tl.q[step]).tolist(), strict=True)),
                "effector_m": tl.effector[step].tolist(),
                "along_line_m": None if tl.along_line is None else float(tl.along_line[step]),
            }
        )
    return {
        "problem": str(result.problem.path),
        "solver": result.solver,
        "strategy": settings.strategy,
        "r_min": settings.r_min,
        "simulated_s": float(tl.time[-1]),
        "half_joints": groups,
        "first_to_fatigue": None
        if not crossings
        else {"half_joint": crossings[0].half_joint, "time_s": crossings[0].time_s},
        "fatigue_recovery_cycles": len(recoveries),
        "recovery_postures": recoveries,
        "task_lost": None
        if lost is None
        else {"time_s": lost.time_s, "half_joint": lost.half_joint, "reason": lost.detail},
        "task_not_held_events": sum(e.kind == "task_not_held" for e in result.events),
        "solver_statistics": {
            "steps": int(tl.time.size),
            "ik_iterations": result.ik_iterations,
            "ik_failures": result.ik_failures,
            "wall_time_s": result.wall_time_s,
            "ik_time_s": result.ik_time_s,
            "share_outside_ik": 1.0 - result.ik_time_s / result.wall_time_s,
        },
    }


def write_results(result: SimulationResult, out: Path) -> list[Path]:
    """Write timeline.csv, events.csv, summary.json and manifest.json into ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / name for name in ("timeline.csv", "events.csv", "summary.json", "manifest.json")]
    _write_timeline(result, paths[0])
    with paths[1].open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(["time_s", "event", "half_joint", "detail"])
        writer.writerows([e.time_s, e.kind, e.half_joint, e.detail] for e in result.events)
    paths[2].write_text(json.dumps(summary(result), indent=2, allow_nan=False) + "\n")
    paths[3].write_text(json.dumps(manifest(result), indent=2, allow_nan=False) + "\n")
    return paths


def manifest(result: SimulationResult) -> dict[str, Any]:
    """Versions, the resolved problem and the solver options of a run."""
    problem = result.problem
    return {
        "package": {"name": "casadi_posture", "version": __version__},
        "casadi": ca.__version__,
        "ipopt": ipopt_version(),
        "numpy": np.__version__,
        "python": platform.python_version(),
        "solver": result.solver,
        "solver_options": problem.spec.solver.model_dump(),
        "constraint_settings": {
            **result.settings.__dict__,
            "max_step_deg": math.degrees(result.settings.max_step),
        },
        "problem": description(problem),
    }


def ipopt_version() -> str:
    """The version of the IPOPT library shipped with CasADi, from its file name (Linux)."""
    names = sorted(p.name for p in Path(ca.__file__).parent.glob("libipopt.so.*.*.*"))
    return names[-1].removeprefix("libipopt.so.") if names else "unknown"


def _write_timeline(result: SimulationResult, path: Path) -> None:
    tl, body = result.timeline, result.problem.body
    dofs, halves = body.dof_names, [h.name for h in body.half_joints]
    levels = result.level_units
    header = ["time_s", *[f"{d}_deg" for d in dofs], *[f"{result.effector}_{a}_m" for a in "xyz"]]
    header += [] if tl.along_line is None else [f"{result.effector}_along_line_m"]
    for kind in ("active", "passive", "external"):
        header += [f"tau_{kind}_{d}_Nm" for d in dofs]
    header += [f"load_{h}_pct_mvc" for h in halves] + [f"fatigue_{h}" for h in halves]
    header += [f"fatigued_{h}" for h in halves]
    header += ["constraint_owner", "goal_angle_deg", "goal_case"]
    header += [f"residual_level{k + 1}_{u.replace(', ', '_')}" for k, u in enumerate(levels)]
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        for i, t in enumerate(tl.time):
            row = [t, *np.degrees(tl.q[i]), *tl.effector[i]]
            row += [] if tl.along_line is None else [tl.along_line[i]]
            row += [*tl.active[i], *tl.passive[i], *tl.external[i], *tl.load[i], *tl.fatigue[i]]
            row += [int(v) for v in tl.fatigued[i]]
            row += [
                halves[tl.owner[i]] if tl.owner[i] >= 0 else "",
                "" if math.isnan(tl.goal[i]) else math.degrees(tl.goal[i]),
                tl.case[i],
            ]
            row += list(tl.residuals[i])
            writer.writerow([f"{v:.10g}" if isinstance(v, float | np.floating) else v for v in row])
