"""One flat row of outcomes per case, the unit of batch summaries, what-if tables and
DataFrames: units in the column names; None (an empty cell) for unlimited endurances,
times that never came, and groups or reasons that do not apply."""

from __future__ import annotations

import math
from typing import Any

from casadi_posture.biomech.capability import SEXES, Capability
from casadi_posture.body.tree import BodyModel
from casadi_posture.output.low_back import run_row
from casadi_posture.output.low_back import static_row as back_row
from casadi_posture.output.results import summary
from casadi_posture.output.scores import row as score_row
from casadi_posture.output.scores import worst
from casadi_posture.simulation import SimulationResult, torque_model
from casadi_posture.static import STRENGTH_PCT_MVC, StaticAnswer, capable_shares, limiting_key


def static_row(answer: StaticAnswer) -> dict[str, Any]:
    """Whether level 1 was reached, each half-joint's load [%MVC] and endurance [min], the
    groups over strength, the limiting group, the share of men and of women capable of the
    task [%], how plausible the posture is (joints near a limit, asymmetry and
    out-of-plane angle [deg], None where the task is neither symmetric nor sagittal), the
    worst RULA and REBA over the sides with their action levels (None: not scored), the
    L5/S1 compression [N] (None: not computed) and the flags (one string)."""
    row: dict[str, Any] = {}
    if answer.levels:
        top = answer.levels[0]
        row |= _reach(top.achieved, top.residual, top.unit)
    start = {g.name: (g.load_pct_mvc, g.endurance_s) for g in answer.groups}
    regions = _regions(answer.problem.body)
    check = answer.plausibility
    return (
        row
        | _endurance(start, regions)
        | _capable(answer.capable)
        | {
            "joints_near_limit": len(check.near_limits) if check else None,
            "asymmetry_deg": check.asymmetry_deg if check else None,
            "out_of_plane_deg": check.out_of_plane_deg if check else None,
            **score_row(worst((0.0, side) for side in answer.scores)),
            **back_row(answer.low_back),
            "flags": "; ".join(answer.flags),
        }
    )


def simulation_row(result: SimulationResult) -> dict[str, Any]:
    """The start outcomes (as ``static_row``; the shares capable at the first posture,
    None when the run has no step) and what the simulation found: when the
    first group reached the fatigue threshold, which group was exhausted and when, the
    cycles, how long the task was held (a lower bound when the run ended with it held),
    the first recovery posture [deg] and its effector position [m], the worst RULA and
    REBA over the run and the sides with their action levels, the peak L5/S1 compression
    [N] and the time above the NIOSH design limit [s], and the flags."""
    report = summary(result)
    task, first, exhausted = report["task"], report["first_to_fatigue"], report["exhausted_group"]
    schedule = report["schedule"]
    start = {
        g["half_joint"]: (
            g["initial_load_pct_mvc"],
            math.inf if g["initial_endurance_min"] is None else 60 * g["initial_endurance_min"],
        )
        for g in report["half_joints"]
    }
    row: dict[str, Any] = (
        _reach(task["held_at_start"], task["level1_residual_at_start"], task["level1_unit"])
        | _endurance(start, _regions(result.problem.body))
        | _capable(
            capable_shares(
                result.problem, torque_model(result.problem).evaluate(result.timeline.q[0])
            )
            if result.timeline.time.size
            else None
        )
        | {
            "simulated_s": report["simulated_s"],
            "stop": report["stop"],
            "first_to_fatigue": first["half_joint"] if first else "",
            "first_to_fatigue_region": first["region"] if first else "",
            "first_fatigue_s": first["time_s"] if first else None,
            "exhausted_group": exhausted["half_joint"] if exhausted else "",
            "exhausted_region": exhausted["region"] if exhausted else "",
            "exhausted_s": exhausted["time_s"] if exhausted else None,
            "fatigue_recovery_cycles": report["fatigue_recovery_cycles"],
            "work_cycles": schedule["work_cycles"] if schedule else None,
            "work_cycles_completed": schedule["work_cycles_completed"] if schedule else None,
            "task_held_s": task["held_s"],
            "task_held_is_lower_bound": task["held_s_is_lower_bound"],
            "task_lost_reason": task["lost"]["reason"] if task["lost"] else "",
            "ik_failures": report["solver_statistics"]["ik_failures"],
            "ik_fallbacks": report["solver_statistics"]["ik_fallbacks"],
            "balance_margin_min_m": report["balance_margin_min_m"],
            **_plausible(report["plausibility"]),
            **score_row(report["rula_reba"]["worst"]),
            **run_row(report["low_back"]),
            "flags": "; ".join(report["flags"]),
        }
    )
    for group in report["half_joints"]:
        row[f"fatigue_threshold_{group['half_joint']}_s"] = group["first_fatigue_threshold_s"]
    recoveries = report["recovery_postures"]
    recovery = recoveries[0] if recoveries else None
    row["recovery_s"] = recovery["time_s"] if recovery else None
    for dof in result.problem.body.dof_names:
        row[f"recovery_{dof}_deg"] = recovery["posture_deg"][dof] if recovery else None
    position = recovery["effector_m"] if recovery else [None] * 3
    for axis, value in zip("xyz", position, strict=True):
        row[f"recovery_{result.effector}_{axis}_m"] = value
    return row


def _plausible(report: dict[str, Any]) -> dict[str, float | None]:
    """The run's largest asymmetry and out-of-plane angle over its key postures [deg] (None:
    not a symmetric or sagittal task) and the longest time a DOF rests on a limit [s]."""

    def most(key: str) -> float | None:
        values = [p[key] for p in report["postures"] if p[key] is not None]
        return max(values, default=None)

    return {
        "max_asymmetry_deg": most("asymmetry_deg"),
        "max_out_of_plane_deg": most("out_of_plane_deg"),
        "longest_at_limit_s": max((h["seconds"] for h in report["held_at_limits"]), default=0.0),
    }


def _capable(capable: Capability | None) -> dict[str, float | None]:
    """The share of each sex capable of the task [%] (its weakest group's)."""
    return {f"capable_{s}_pct": None if capable is None else capable.share(s) for s in SEXES}


def _reach(reached: bool, residual: float | None, unit: str) -> dict[str, Any]:
    return {"reached": reached, f"residual_level1_{unit.replace(', ', '_')}": residual}


def _regions(body: BodyModel) -> dict[str, str]:
    return {h.name: h.region for h in body.half_joints}


def _endurance(
    groups: dict[str, tuple[float | None, float]], regions: dict[str, str]
) -> dict[str, Any]:
    """Each half-joint's start load [%MVC] and endurance [min], the groups over strength, and
    the limiting group at the start and its body region: the shortest endurance (empty when
    no group tires)."""
    row: dict[str, Any] = {}
    for name, (load, seconds) in groups.items():
        row[f"initial_load_{name}_pct_mvc"] = load
        row[f"initial_endurance_{name}_min"] = seconds / 60
    tiring = [name for name, (_, seconds) in groups.items() if math.isfinite(seconds)]
    limiting = min(
        tiring, key=lambda n: limiting_key(groups[n][1], groups[n][0] or 0.0), default=None
    )
    over = [name for name, (load, _) in groups.items() if (load or 0.0) > STRENGTH_PCT_MVC]
    return row | {
        "over_strength_at_start": "+".join(over),
        "limiting_group_at_start": limiting or "",
        "limiting_region_at_start": "" if limiting is None else regions[limiting],
        "limiting_endurance_at_start_min": None if limiting is None else groups[limiting][1] / 60,
    }
