"""The paper's wall experiment on the standing body (README.md, docs/scenarios.md): the
shipped example ``examples/wall_protocol.py`` runs it; this module turns its runs into the
documents' table and the values of their prose."""

from __future__ import annotations

import importlib.util
import math
from functools import cache
from types import ModuleType
from typing import Any

import casadi_posture as cp

from . import parallel
from .regions import Region
from .session import ROOT, Session

#: The lines by the names the templates use: the problem's stem, the table's label.
LINES = {
    "horizontal": "standing_wall_horizontal",
    "m25": "standing_wall_m25",
    "m45": "standing_wall_m45",
}
#: The groups whose loads the documents follow.
GROUPS = ("shoulder_flexors_r", "elbow_flexors_r")
LABELS = {"horizontal": "0°", "m25": "−25°", "m45": "−45°"}

#: The example's variants (``VARIANTS``: the file's whole-body adjustment, the paper's law
#: active and passive with the constraint alone, active with the wrist kept on the line)
#: by the names the templates use, in the example's order.
VARIANTS = ("whole", "paper0", "paper0_passive", "paper2")
#: Further runs of the paper's law on the horizontal line (active, the constraint alone):
#: with the lexicographic solver alone, and with the comfort level's displacement term alone.
CHECKS: dict[str, dict[str, Any]] = {
    "paper0_lexicographic": {"solver.name": "lexicographic"},
    "paper0_displacement": {"tasks[5].measure": "joint_displacement"},
}
#: Every run: each line under each variant, and the checks on the horizontal line.
CASES = [(line, v) for line in LINES for v in VARIANTS] + [("horizontal", v) for v in CHECKS]
#: A joint within this of a limit [deg] is at it.
AT_LIMIT_DEG = 0.5


@cache
def example() -> ModuleType:
    """examples/wall_protocol.py, imported."""
    spec = importlib.util.spec_from_file_location(
        "wall_protocol", ROOT / "examples" / "wall_protocol.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run(line: str, variant: str) -> cp.Simulation:
    """One line's file under one variant, simulated for the file's duration."""
    base = cp.load(ROOT / "problems" / f"{LINES[line]}.toml")
    if variant in CHECKS:
        keys = example().VARIANTS[VARIANTS.index("paper0")][1] | CHECKS[variant]
    else:
        keys = example().VARIANTS[VARIANTS.index(variant)][1]
    return cp.simulate(cp.from_dict(base.data, str(base.path), keys))


def group(half_joint: str | None) -> str:
    """'shoulder_flexors_r' → 'shoulder flexors'."""
    return example().group(half_joint or "")


def facts(line: str, variant: str) -> dict[str, Any]:
    """:func:`run_facts` of one run, all of them computed at once in parallel."""
    return all_facts()[line, variant]


def prefetch() -> None:
    """Start every run in the background."""
    parallel.submit(run_facts, CASES)


@cache
def all_facts() -> dict[tuple[str, str], dict[str, Any]]:
    """:func:`run_facts` of every line under every variant."""
    return parallel.compute(run_facts, CASES)


def run_facts(line: str, variant: str) -> dict[str, Any]:
    """What the documents say of one run: its summary, ``row`` (the example's table row),
    ``recoveries`` (the example's :class:`Recovery` of each release, ``along_back_m`` the
    distance drawn back along the line [m], ``group`` the owner released), ``first_s`` and
    ``first_group`` (the first group at the threshold), ``lost_s``, ``lost_min``,
    ``lost_group`` (None when held), ``thresholds`` (each half-joint's first time at the
    threshold [s], by its name), ``final_fatigue``, ``fallbacks``, ``steps``, and ``loads``
    of the right shoulder and elbow flexors [%MVC]: ``min`` and ``max`` over the run,
    ``at_recoveries`` and ``after_first_recovery_max``; ``pronation_at_limit_from_s`` (the
    first time the right forearm is at a pronation limit [s]) and
    ``lumbar_after_first_recovery_min_deg`` (the lumbar spine's least flexion [deg] from
    the first recovery on); ``frame``, the timeline by time [s], and ``events``, each event's
    (time [s], kind, half-joint)."""
    simulation = run(line, variant)
    s, frame = simulation.summary(), simulation.to_frame().set_index("time_s")
    first, lost = s["first_to_fatigue"], s["task"]["lost"]
    recoveries = [
        r._asdict() | {"along_back_m": -r.along_m, "group": group(p["half_joint"])}
        for r, p in zip(
            example().recovery_positions(simulation), s["recovery_postures"], strict=True
        )
    ]
    row = None
    if variant in VARIANTS:
        label = example().VARIANTS[VARIANTS.index(variant)][0]
        row = example().row(LABELS[line], label, simulation)
    body = simulation.result.problem.body
    pronation = frame["forearm_pronation_r_deg"]
    limits = [math.degrees(b[body.index["forearm_pronation_r"]]) for b in (body.lower, body.upper)]
    at_limit = pronation[
        (pronation - limits[0] < AT_LIMIT_DEG) | (limits[1] - pronation < AT_LIMIT_DEG)
    ]
    after = frame.loc[recoveries[0]["time_s"] :] if recoveries else frame.iloc[0:0]
    return s | {
        "row": row,
        "pronation_at_limit_from_s": at_limit.index.min() if len(at_limit) else None,
        "lumbar_after_first_recovery_min_deg": after["lumbar_flexion_deg"].min(),
        "recoveries": recoveries,
        "first_s": first["time_s"] if first else None,
        "first_group": group(first["half_joint"]) if first else None,
        "lost_s": lost["time_s"] if lost else None,
        "lost_min": lost["time_s"] / 60 if lost else None,
        "lost_group": group(lost["half_joint"]) if lost else None,
        "thresholds": {h["half_joint"]: h["first_fatigue_threshold_s"] for h in s["half_joints"]},
        "final_fatigue": {h["half_joint"]: h["final_fatigue"] for h in s["half_joints"]},
        "loads": {
            g: {
                "min": frame[f"load_{g}_pct_mvc"].min(),
                "max": frame[f"load_{g}_pct_mvc"].max(),
                "at_recoveries": [frame.at[r["time_s"], f"load_{g}_pct_mvc"] for r in recoveries],
                "after_first_recovery_max": frame[f"load_{g}_pct_mvc"]
                .loc[recoveries[0]["time_s"] if recoveries else frame.index[-1] :]
                .max(),
            }
            for g in GROUPS
        },
        "fallbacks": s["solver_statistics"]["ik_fallbacks"],
        "frame": frame,
        "events": [(e.time_s, e.kind, e.half_joint) for e in simulation.result.events],
        "steps": s["solver_statistics"]["steps"],
    }


def back(along_back_m: float) -> str:
    """How far the wrist was drawn back along the line: '0.20 m back', or 'at the dot'."""
    return f"{along_back_m:.2f} m back" if abs(along_back_m) >= 0.005 else "at the dot"


def outcome(f: dict[str, Any]) -> str:
    """A table cell: the recovery positions, the cycles and how the hold ended."""
    if f["recoveries"]:
        positions = ", ".join(
            f"{r['height_m']:.2f} m, {r['distance_m']:.2f} m ({back(r['along_back_m'])}) "
            f"at {r['time_s']:.0f} s"
            for r in f["recoveries"]
        )
        owners = sorted({r["group"] for r in f["recoveries"]})
        if len(owners) > 1:
            positions += (
                " (released by "
                + ", ".join(
                    f"the {o} at "
                    + " and ".join(f"{r['time_s']:.0f}" for r in f["recoveries"] if r["group"] == o)
                    + " s"
                    for o in owners
                )
                + ")"
            )
    else:
        positions = "no recovery"
    cycles = f["fatigue_recovery_cycles"]
    if f["lost_s"] is None:
        end = f"held the whole {f['duration_s'] / 60:.0f} minutes"
    else:
        end = f"the {f['lost_group']} exhausted at {f['lost_min']:.1f} min"
    fell = (
        f"; {f['fallbacks']} of {f['steps']} steps fell back to the other solver"
        if f["fallbacks"]
        else ""
    )
    return f"{positions}; {cycles} cycle{'s' * (cycles != 1)}; {end}{fell}"


def example_table(region: Region, session: Session) -> str:
    """The table ``python examples/wall_protocol.py`` prints (docs/comfort.md)."""
    rows = [example().HEADER]
    for line, stem in LINES.items():
        rows += [facts(line, v)["row"] for v in VARIANTS]
        rows.append(example().paper_row(LABELS[line], cp.load(ROOT / "problems" / f"{stem}.toml")))
    return "\n".join(rows)


def table(region: Region, session: Session) -> str:
    """The wall table of docs/scenarios.md: the paper, the whole-body adjustment, the
    paper's law with the constraint alone (active; the passive runs named where they
    differ) and with the wrist kept on the line."""
    paper = {label: text for label, _, text in example().LINES}
    rows = [
        "| line | the paper (12 people) | whole-body adjustment (the files') | the paper's law, "
        "active or passive (`keep_levels = 0`) | the paper's law, wrist kept on the line "
        "(`keep_levels = 2`) |",
        "|---|---|---|---|---|",
    ]
    for line, label in LABELS.items():
        active, passive = facts(line, "paper0"), facts(line, "paper0_passive")
        law = outcome(active)
        if outcome(passive) != law:
            law += f" (passive: {outcome(passive)})"
        cells = (
            label,
            paper[label] + "; repeated cycles",
            outcome(facts(line, "whole")),
            law,
            outcome(facts(line, "paper2")),
        )
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def start(line: str) -> dict[str, Any]:
    """The start posture of a line's file: ``groups`` (each group's ``strength_Nm``,
    ``torque_Nm``, ``load_pct_mvc`` and ``endurance_min``, by name), ``shoulder_deg`` (the
    right shoulder's flexion [deg] in the solved posture) and the dot's ``height_m`` above
    the floor and ``distance_m`` from the right shoulder's joint centre [m]."""
    problem = cp.load(ROOT / "problems" / f"{LINES[line]}.toml")
    answer = cp.solve(problem)
    height, distance = (float(v) for v in example().wrist_position(problem)(problem.posture))
    return {
        "groups": answer.to_frame().set_index("name").to_dict("index"),
        "shoulder_deg": answer.posture_deg["shoulder_flexion_r"],
        "height_m": height,
        "distance_m": distance,
    }


def values(region: Region, session: Session) -> dict[str, Any]:
    """:func:`every_line` (computed once per run of the generators)."""
    return every_line()


@cache
def every_line() -> dict[str, Any]:
    """The facts of every run, by line and variant (``{m45[paper2][lost_s]:.0f}``), with
    the line's ``start`` (:func:`start`) and ``first_s_all`` (the first threshold's time
    [s] when every run of the line has the same one, else None); ``all`` holds the
    ``first_s`` every run shares (else None) and the number of ``runs``."""
    found: dict[str, Any] = {}
    for line in LINES:
        runs = {v: facts(line, v) for v in VARIANTS}
        firsts = {f["first_s"] for f in runs.values()}
        if line == "horizontal":
            runs |= {v: facts(line, v) for v in CHECKS}
        found[line] = runs | {
            "start": start(line),
            "first_s_all": firsts.pop() if len(firsts) == 1 else None,
        }
    common = {found[line]["first_s_all"] for line in LINES}
    found["all"] = {
        "first_s": common.pop() if len(common) == 1 else None,
        "runs": len(LINES) * len(VARIANTS),
    }
    return found


#: The paper's recovery height on its −25° line (Fig. 12) [m], a quotation.
PAPER_HEIGHT_M = 1.40


def reach() -> dict[str, Any]:
    """The right arm on the −25° file beside the paper's protocol: ``reach_m``, the
    wrist's distance from the shoulder with the elbow straight, the dot's ``dot_height_m``
    and ``dot_distance_m`` (the wrist at the start), and how far the paper's
    ``paper_height_m`` lies ``above_dot_m`` [m]."""
    problem = cp.load(ROOT / "problems" / f"{LINES['m25']}.toml")
    wrist = example().wrist_position(problem)
    straight = [float(v) for v in problem.posture]
    straight[problem.body.index["elbow_flexion_r"]] = 0.0
    height, distance = (float(v) for v in wrist(problem.posture))
    return {
        "reach_m": float(wrist(straight)[1]),
        "dot_height_m": height,
        "dot_distance_m": distance,
        "paper_height_m": PAPER_HEIGHT_M,
        "above_dot_m": PAPER_HEIGHT_M - height,
    }
