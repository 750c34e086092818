"""The paper's wall experiment (§6) on the 29-DOF standing body, under the whole-body
adjustment the files ship and under the paper's own law, beside what the paper reports:
one markdown table of the recovery positions (wrist height above the floor, distance from
the right shoulder's joint centre), the cycles and the time the wrist was held on the line.

Run: python examples/wall_protocol.py [DURATION_S]
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import casadi as ca

import casadi_posture as cp
from casadi_posture.output.key_postures import recoveries

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

#: The three lines of the paper: label, problem file, what the paper reports on it.
LINES = (
    ("0°", "standing_wall_horizontal", "one recovery position, 0.60 m from the shoulder"),
    ("−25°", "standing_wall_m25", "one recovery position, 1.40 m above the floor"),
    (
        "−45°",
        "standing_wall_m45",
        "that position, and a second one downward (a passive strategy, some subjects)",
    ),
)

#: Each variant: its label in the table and the keys it sets (none: the file's own).
VARIANTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("whole body, keep 2 (the file's)", {}),
    (
        "paper, active, keep 0",
        {"fatigue.adjustment": "paper", "fatigue.strategy": "active", "fatigue.keep_levels": 0},
    ),
    (
        "paper, passive, keep 0",
        {"fatigue.adjustment": "paper", "fatigue.strategy": "passive", "fatigue.keep_levels": 0},
    ),
    (
        "paper, active, keep 2",
        {"fatigue.adjustment": "paper", "fatigue.strategy": "active", "fatigue.keep_levels": 2},
    ),
)

#: Two recoveries closer than this [m] in height and distance are one position.
SAME_POSITION_M = 0.005

#: A line residual [m] above this at a recovery: the wrist was off the line there.
ON_LINE_M = 1e-4


class Recovery(NamedTuple):
    """A recovery posture: when [s], the wrist's height above the floor and distance from
    the right shoulder's joint centre [m], how far it moved along the line from the dot
    (negative: back) and off the line [m]."""

    time_s: float
    height_m: float
    distance_m: float
    along_m: float
    off_line_m: float


def wrist_position(problem: cp.Problem) -> ca.Function:
    """q [rad] ↦ (wrist height above the floor, its distance from the right shoulder's
    joint centre) [m]; the floor is z = 0 for a standing body."""
    body = problem.body
    wrist, shoulder = body.landmark("wrist_r"), body.landmark("shoulder_r")
    return ca.Function("wrist", [body.q], [wrist[2], ca.norm_2(wrist - shoulder)])


def recovery_positions(run: cp.Simulation) -> list[Recovery]:
    """Every recovery posture of ``run`` (the constraint's releases)."""
    result = run.result
    tl, position = result.timeline, wrist_position(result.problem)
    line_level = 1  # the wrist on the line is level 2
    out = []
    for step in recoveries(result):
        height, distance = (float(v) for v in position(tl.q[step]))
        along = float(tl.along_line[step]) if tl.along_line is not None else float("nan")
        off = float(tl.residuals[step, line_level])
        out.append(Recovery(float(tl.time[step]), height, distance, along, off))
    return out


def positions_text(found: Sequence[Recovery]) -> str:
    """The distinct recovery positions: 'height m, distance m (along the line; times)'."""
    if not found:
        return "none"
    groups: list[list[Recovery]] = []
    for r in found:
        same = next(
            (
                g
                for g in groups
                if abs(g[0].height_m - r.height_m) < SAME_POSITION_M
                and abs(g[0].distance_m - r.distance_m) < SAME_POSITION_M
            ),
            None,
        )
        if same is None:
            groups.append([r])
        else:
            same.append(r)
    parts = []
    for g in groups:
        r = g[0]
        when = ", ".join(f"{x.time_s:.0f}" for x in g)
        off = f", off the line {r.off_line_m:.3f} m" if r.off_line_m > ON_LINE_M else ""
        parts.append(
            f"{r.height_m:.2f} m, {r.distance_m:.2f} m ({r.along_m:+.2f} m along{off}; {when} s)"
        )
    return "; ".join(parts)


def held_text(summary: Mapping[str, Any]) -> str:
    """How long the wrist stayed on the line [min], and what ended it."""
    task = summary["task"]
    if task["held_s_is_lower_bound"] and summary["simulated_s"] >= summary["duration_s"]:
        return f"{summary['duration_s'] / 60:g} (whole run)"
    lost = task["lost"]
    why = f" ({group(lost['half_joint'])} exhausted)" if lost and lost["half_joint"] else ""
    return f"{task['held_s'] / 60:.1f}{why}"


def group(half_joint: str) -> str:
    """A right-side group's name as the table writes it: 'shoulder flexors'."""
    return half_joint.removesuffix("_r").replace("_", " ")


def row(line: str, variant: str, run: cp.Simulation) -> str:
    """One line of the table for one run."""
    s = run.summary()
    first = s["first_to_fatigue"]
    tires = f"{group(first['half_joint'])} ({first['time_s']:.0f} s)" if first else "none"
    stats = s["solver_statistics"]
    cells = (
        line,
        variant,
        positions_text(recovery_positions(run)),
        str(s["fatigue_recovery_cycles"]),
        held_text(s),
        tires,
        f"{stats['ik_fallbacks']}/{stats['steps']}",
    )
    return "| " + " | ".join(cells) + " |"


def paper_row(label: str, base: cp.Problem) -> str:
    """The row of what the paper reports on the line ``label``, beside our dot."""
    paper = next(text for name, _, text in LINES if name == label)
    height, distance = (float(v) for v in wrist_position(base)(base.posture))
    ours = f"our dot: {height:.2f} m high, {distance:.2f} m from the shoulder"
    return (
        f"| {label} | the paper (12 people) | {paper} ({ours}) | repeated | not given "
        "| not given | |"
    )


HEADER = (
    "| line | law, strategy, kept levels | recovery positions: wrist height above the floor, "
    "distance from the shoulder (moved along the line; when) | cycles | held [min] "
    "| first at the threshold | fallbacks/steps |\n|---|---|---|---|---|---|---|"
)


def main(
    duration_s: float | None = None,
    lines: Sequence[tuple[str, str, str]] = LINES,
    variants: Sequence[tuple[str, dict[str, Any]]] = VARIANTS,
) -> list[str]:
    """Run every variant on every line (the file's duration, or ``duration_s``) and print
    the table; returns its rows."""
    start = time.perf_counter()
    extra = {} if duration_s is None else {"simulation.duration_s": duration_s}
    rows = []
    for label, stem, _ in lines:
        base = cp.load(PROBLEMS / f"{stem}.toml")
        for name, keys in variants:
            problem = cp.from_dict(base.data, str(base.path), keys | extra)
            rows.append(row(label, name, cp.simulate(problem)))
        rows.append(paper_row(label, base))
    print(HEADER)
    print("\n".join(rows))
    print(f"\nwall time {time.perf_counter() - start:.0f} s")
    return rows


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else None)
