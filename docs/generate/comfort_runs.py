"""docs/comfort.md: the comfort measure's shipped numbers (``comfort-data``, from
``comfort.toml``), the shipped problems under the paper's and the whole-body adjustment
(``comfort-adjustments``: a table and the values of the prose) and the standing wall
without its posture task (``comfort-free-wall``)."""

from __future__ import annotations

from typing import Any

from casadi_posture.data import parameters

from . import low_back, parallel, shipped_runs, wall
from .regions import Region
from .session import Session

#: The table's rows: the problem's name in :mod:`shipped_runs` and its label.
ROWS = {
    "wall": "standing wall 0° (protocol)",
    "shelf": "standing shelf (both hands)",
    "drill": "overhead drill",
    "seated": "seated assembly",
}
#: The runs of each column: the problem's name → the variant.
COLUMNS = {
    "paper": {"wall": "paper", "shelf": "shipped", "drill": "shipped", "seated": "shipped"},
    "whole": {
        "wall": "shipped",
        "shelf": "whole_body",
        "drill": "whole_body",
        "seated": "whole_body",
    },
}
#: The DOFs whose angles at the recoveries the table quotes, with their words.
AT_RECOVERY = {
    "lumbar_rotation": "the lumbar spine turned",
    "lumbar_bending": "bent sideways",
    "shoulder_abduction_r": "the right shoulder abducted",
}


def prefetch() -> None:
    """Start the page's runs in the background."""
    shipped_runs.prefetch([(n, v) for runs in COLUMNS.values() for n, v in runs.items()])
    shipped_runs.prefetch([("wall", "free_wall")])
    parallel.submit(wall.run_facts, [("horizontal", "paper0_lexicographic")])


def most(postures: list[dict[str, Any]], dof: str) -> float | None:
    """The largest absolute angle [deg] of ``dof`` over the recovery postures."""
    return max((abs(p["posture_deg"][dof]) for p in postures), default=None)


def facts(name: str, variant: str) -> dict[str, Any]:
    """What the page says of one run: the summary, ``first_s``, ``recoveries_s`` (text),
    ``turn_deg``, ``bend_deg`` and ``abduction_deg`` (the largest at the recoveries [deg],
    None without one), ``start_turn_deg`` (the lumbar rotation at the start [deg]),
    ``held_min`` and ``max_turn_deg`` (the largest lumbar rotation over the run [deg],
    None for a run the wall or low-back generators make)."""
    s = shipped_runs.summary(name, variant)
    postures = s["recovery_postures"]
    first = s["first_to_fatigue"]
    return s | {
        "first_s": first["time_s"] if first else None,
        "recoveries_s": ", ".join(f"{p['time_s']:.0f}" for p in postures) or "none",
        "turn_deg": most(postures, "lumbar_rotation"),
        "bend_deg": most(postures, "lumbar_bending"),
        "abduction_deg": most(postures, "shoulder_abduction_r"),
        "start_turn_deg": abs(shipped_runs.start(name, variant).posture_deg["lumbar_rotation"]),
        "held_min": s["task"]["held_s"] / 60,
        "max_turn_deg": (
            max(abs(e) for e in s["extremes"]["lumbar_rotation"].values())
            if "extremes" in s
            else None
        ),
    }


#: The plausibility flags' kinds, by a phrase of their text, in the order the cells name them.
KINDS = {
    "held asymmetrically": "asymmetric",
    "trunk twisted or bent sideways": "trunk twisted or bent sideways",
    "trunk leans back": "trunk leaning back",
    "crossed": "forearms crossed",
}
#: A DOF within this of its neutral angle [deg] has not moved.
STILL_DEG = 0.5


def kinds(flags: list[str]) -> str:
    """The flags' kinds ('asymmetric, trunk twisted or bent sideways, 7 DOFs resting on a
    limit'), or 'none'."""
    found = [word for phrase, word in KINDS.items() if any(phrase in f for f in flags)]
    resting = sum("rests on its" in f for f in flags)
    if resting:
        found.append(f"{resting} DOF{'s' * (resting != 1)} resting on a limit")
    return ", ".join(found) or "none"


def cell(f: dict[str, Any]) -> str:
    """A table cell: the first threshold, the recoveries (and the wrist drawn back on the
    wall), how the hold ended, the trunk at the start and at the recoveries, the fallbacks
    and the flags."""
    parts = [f"threshold at {f['first_s']:.0f} s" if f["first_s"] is not None else "no threshold"]
    cycles = f["fatigue_recovery_cycles"]
    if cycles:
        parts.append(f"{cycles} cycle{'s' * (cycles != 1)} (recovering at {f['recoveries_s']} s)")
        moved = [
            f"{words} {most(f['recovery_postures'], dof):.0f}°"
            for dof, words in AT_RECOVERY.items()
            if most(f["recovery_postures"], dof) >= STILL_DEG
        ]
        if moved:
            parts.append(", ".join(moved) + " at the recoveries")
    for r in f.get("recoveries", []):
        parts.append(
            f"the wrist drawn {r['along_back_m']:.2f} m back along the line at {r['time_s']:.0f} s"
        )
    if f["start_turn_deg"] >= STILL_DEG:
        parts.append(f"the lumbar spine turned {f['start_turn_deg']:.0f}° at the start")
    lost = f["task"]["lost"]
    if lost is None:
        parts.append(f"held {f['duration_s'] / 60:.0f} min")
    else:
        parts.append(f"the {wall.group(lost['half_joint'])} exhausted at {lost['time_s']:.0f} s")
    statistics = f["solver_statistics"]
    parts.append(
        f"{statistics['ik_fallbacks']} of {statistics['steps']} steps fell back to the other solver"
    )
    parts.append(f"flagged: {kinds(f['plausibility']['flags'])}")
    return "; ".join(parts)


def adjustments(region: Region, session: Session) -> dict[str, Any]:
    """``table``: :data:`ROWS` under both adjustments; ``paper[NAME]`` and ``whole[NAME]``:
    :func:`facts` of each run; ``wall_paper``: the wall generator's facts of the paper's
    law on the 0° line (``pronation_at_limit_from_s``), ``wall_lexicographic`` the same
    with the lexicographic solver alone."""
    found = {c: {n: facts(n, v) for n, v in runs.items()} for c, runs in COLUMNS.items()}
    rows = ["| problem | paper's adjustment | whole-body adjustment |", "|---|---|---|"]
    rows += [
        f"| {label} | {cell(found['paper'][n])} | {cell(found['whole'][n])} |"
        for n, label in ROWS.items()
    ]
    return found | {
        "table": "\n".join(rows),
        "wall_paper": wall.facts("horizontal", "paper0"),
        "wall_lexicographic": wall.facts("horizontal", "paper0_lexicographic"),
    }


def free_wall(region: Region, session: Session) -> dict[str, Any]:
    """The standing wall without its ``sagittal_plane`` task under the paper's law:
    ``least[DOF]`` and ``most[DOF]``, each DOF's extreme angles over the run [deg]
    (``least_text[DOF]``: with a typographic minus, '−44'), and the body's ``dofs``."""
    extremes = shipped_runs.summary("wall", "free_wall")["extremes"]
    return {
        "dofs": len(extremes),
        "least_text": {d: low_back.minus(e["min"]) for d, e in extremes.items()},
        "least": {d: e["min"] for d, e in extremes.items()},
        "most": {d: e["max"] for d, e in extremes.items()},
    }


def data(region: Region, session: Session) -> dict[str, Any]:
    """The comfort measure's shipped numbers: ``p[NAME]`` every parameter of comfort.toml
    by its name without the file's prefix (``{p[limit_zone]:g}``), and ``joint_weights``:
    '1 for every DOF' when every γ_i is the same, else each DOF's."""
    table = {k.removeprefix("comfort."): v.value for k, v in parameters.load("comfort").items()}
    weights = {
        k.removeprefix("joint_weight."): v
        for k, v in table.items()
        if k.startswith("joint_weight.")
    }
    if len(set(weights.values())) == 1:
        text = f"{next(iter(weights.values())):g} for every DOF"
    else:
        text = ", ".join(f"{d} {w:g}" for d, w in weights.items())
    return {"p": table, "joint_weights": text}


def wall_recoveries(region: Region, session: Session) -> dict[str, Any]:
    """The wall lines' whole-body recoveries beside the paper's: ``back_min`` and
    ``back_max``, how far the wrist was drawn back along the line [m] over every recovery
    of the three lines; the right arm's ``reach_m`` (the wrist's distance from the
    shoulder, the elbow straight, in the files' start posture) and ``above_dot_m``, how far
    the paper's ``paper_height_m`` lies above the dot [m]."""
    backs = [
        r["along_back_m"] for line in wall.LINES for r in wall.facts(line, "whole")["recoveries"]
    ]
    return wall.reach() | {"back_min": min(backs), "back_max": max(backs)}
