"""A run's outcome in words, from its summary.json: what limited it, what tired first,
what gave out, how long the task was held (the console's and report.html's lines)."""

from __future__ import annotations

from typing import Any


def time_text(seconds: float) -> str:
    """A time in seconds, and in minutes from one minute on (as the figures' axes)."""
    return f"{seconds:g} s ({seconds / 60:.1f} min)" if seconds >= 60 else f"{seconds:g} s"


def outcome_lines(report: dict[str, Any]) -> list[str]:
    """The outcome of a simulation in words: limiting group, first to tire, cycles, task."""
    limiting, first = report["limiting_group_at_start"], report["first_to_fatigue"]
    exhausted, task = report["exhausted_group"], report["task"]
    lines = [
        "limiting group at start (shortest endurance): "
        + (
            f"{limiting['half_joint']} ({limiting['region']}, {limiting['endurance_min']:.2f} min)"
            if limiting
            else "none (no group tires)"
        ),
        "first at the fatigue threshold: "
        + (
            f"{first['half_joint']} ({first['region']}) at {time_text(first['time_s'])}"
            if first
            else "none"
        ),
        "exhausted: "
        + (
            f"{exhausted['half_joint']} ({exhausted['region']}) at {time_text(exhausted['time_s'])}"
            f" ({exhausted['cause']})"
            if exhausted
            else "none"
        ),
    ]
    if report["stop"] == "interrupted" and not report["solver_statistics"]["steps"]:
        lines.append("task: no step was run")
    elif task.get("recorded"):
        lines.append(_recorded(task))
    elif not task["held_at_start"]:
        lines.append(f"task never held: {task['lost']['reason'] if task['lost'] else 'no step'}")
    elif task["lost"]:
        lines.append(f"task held {time_text(task['held_s'])}, then lost: {task['lost']['reason']}")
    else:
        lines.append(f"task held ≥ {time_text(task['held_s'])} (to the end of the run)")
    lines.append(f"fatigue/recovery cycles: {report['fatigue_recovery_cycles']}")
    if report.get("schedule"):
        s = report["schedule"]
        lines.append(
            f"work-rest schedule: hold {s['hold_s']:g} s, rest {s['rest_s']:g} s; "
            f"{s['work_cycles']} work cycles ({s['work_cycles_completed']} held to their end), "
            f"{s['time_holding_s']:g} s holding, {s['time_resting_s']:g} s resting"
        )
    return lines


def _recorded(task: dict[str, Any]) -> str:
    """How long the model's groups hold a recorded motion, and how far it is from level 1."""
    if task["lost"]:
        held = f"the model's groups hold the recording {time_text(task['held_s'])}: "
        held += task["lost"]["reason"]
    else:
        held = f"the model's groups hold the whole recording ({time_text(task['held_s'])})"
    if task["level1"] is None:
        return held
    return (
        f"{held}; level 1 ({task['level1']}) residual {task['level1_residual_at_start']:.3g} "
        f"{task['level1_unit']} at the first frame, {task['level1_residual_max']:.3g} at most"
    )
