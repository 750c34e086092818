"""The prose of docs/scenarios.md that the wall and holding generators do not write: how
the two solvers agree on the standing wall, where the paper's recovery heights lie on our
body (``casadi-posture solve`` with the wrist's target moved), the −45° line's cycles
under the whole-body adjustment, the joint limits the paper's law drives the body to,
and the workplace table (``scenarios``). The wall's runs are the wall generator's; only
the lexicographic solver's runs of its files are added here."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from functools import cache
from typing import Any

import casadi as ca
import numpy as np
import pandas as pd

import casadi_posture as cp
from casadi_posture.data import parameters

from . import arm_figures, paper_arm, parallel, wall
from .regions import Region
from .session import ROOT, Session

#: How far down the −45° line from the dot the shoulder flexors are solved for [m].
DOWN_M = (0.05, 0.10)
#: The wrist's target task of the wall files (``tasks[4]``).
TARGET_TASK = 4
#: A joint within this of a limit [deg] is at it.
AT_LIMIT_DEG = wall.AT_LIMIT_DEG
#: A fall of the owner's load larger than this in one step [%MVC]: the adjustment is still
#: under way.
SETTLING_PCT = 0.5
#: The groups whose loads the −45° narrative follows.
SHOULDER, ELBOW = wall.GROUPS


def timeline(stem: str, keys: tuple[tuple[str, Any], ...]) -> dict[str, Any]:
    """A shipped problem simulated with ``keys`` (in a form that pickles): its ``summary``,
    ``frame`` (the timeline by time [s]) and ``events`` ((time [s], kind, half-joint))."""
    simulation = cp.simulate(cp.load(ROOT / "problems" / f"{stem}.toml", dict(keys)))
    return {
        "summary": simulation.summary(),
        "frame": simulation.to_frame().set_index("time_s"),
        "events": [(e.time_s, e.kind, e.half_joint) for e in simulation.result.events],
    }


LEXICOGRAPHIC = (("solver.name", "lexicographic"),)
#: The wall files under the lexicographic solver (the whole-body adjustment they ship).
SOLVER_CASES = [(stem, LEXICOGRAPHIC) for stem in wall.LINES.values()]


def prefetch() -> None:
    """Start the wall's runs and the lexicographic ones in the background."""
    wall.prefetch()
    parallel.submit(timeline, SOLVER_CASES + WORKPLACE_CASES)


def postures_apart_deg(a: pd.DataFrame, b: pd.DataFrame) -> float:
    """The largest difference of any joint angle between two timelines [deg] (inf when
    they have different steps)."""
    angles = [c for c in a.columns if c.endswith("_deg") and c != "goal_angle_deg"]
    if not a.index.equals(b.index):
        return math.inf
    return float((a[angles] - b[angles]).abs().to_numpy().max())


def at_most(value: float) -> str:
    """A bound with one significant digit, rounded up: 2.7e-06 → '3e-6', 0 → '0'."""
    if value == 0:
        return "0"
    exponent = math.floor(math.log10(value))
    mantissa = math.ceil(round(value / 10**exponent, 9))
    if mantissa == 10:
        mantissa, exponent = 1, exponent + 1
    return f"{mantissa}e{exponent}" if abs(exponent) > 2 else f"{mantissa * 10.0**exponent:g}"


def listed(items: list[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def on_lines(labels: list[str]) -> str:
    """['0°', '−25°'] → 'on the 0° and −25° lines'."""
    return f"on the {listed(labels)} line{'s' * (len(labels) > 1)}"


def dof_name(dof: str) -> str:
    """'shoulder_flexion_r' → "right shoulder's flexion", 'lumbar_flexion' → "lumbar flexion"."""
    joint, _, side = dof.rpartition("_")
    if side not in ("r", "l"):
        return dof.replace("_", " ")
    base, _, motion = joint.rpartition("_")
    return f"{'right' if side == 'r' else 'left'} {base.replace('_', ' ')}'s {motion}"


#: Two runs whose joint angles differ by more than this [deg] at a step have parted.
PARTED_DEG = 1.0


def parting(a: dict[str, Any], b: dict[str, Any], names: tuple[str, str]) -> str:
    """How two runs of one file that do not agree part: the step their postures part at,
    the joint that moves most apart there, and the first event that differs."""
    angles = [c for c in a["frame"].columns if c.endswith("_deg") and c != "goal_angle_deg"]
    apart = (a["frame"][angles] - b["frame"][angles]).abs()
    parted = apart.index[(apart.max(axis=1) > PARTED_DEG).to_numpy()]
    text = []
    if len(parted):
        t = parted[0]
        joint = apart.loc[t].idxmax()
        before = apart.loc[:t].iloc[:-1].to_numpy().max()
        text.append(
            f"the postures agree within {at_most(before)}° until {t:.0f} s, when the "
            f"{names[1]} solver takes the {dof_name(joint.removesuffix('_deg'))} from "
            f"{arm_figures.minus(b['frame'][joint].shift().loc[t], 0)}° to "
            f"{arm_figures.minus(b['frame'][joint].loc[t], 0)}° in one step (the {names[0]} "
            f"solver: {arm_figures.minus(a['frame'][joint].loc[t], 0)}°)"
        )
    for x, y in zip([*a["events"], None], [*b["events"], None], strict=False):
        if x != y:
            shown = [
                f"{wall.group(e[2])}' {e[1].replace('_', ' ')} at {e[0]:.0f} s" if e else "none"
                for e in (y, x)
            ]
            text.append(
                f"the first event that differs is the {shown[0]} ({names[0]}: the {shown[1]})"
            )
            break
    return "; ".join(text)


def agreement(
    pairs: Mapping[str, tuple[dict[str, Any], dict[str, Any]]],
    where: Callable[[list[str]], str] = on_lines,
    names: tuple[str, str] = ("nullspace", "lexicographic"),
) -> dict[str, str]:
    """How two solvers' runs of the same files agree, as text: ``pairs`` holds, by a
    label, each file's run with one solver and with the other (``frame``, ``events``,
    ``summary``); ``where`` names labels in a sentence. ``agree``: where the events are
    the same at the same seconds and the postures within a bound [deg] (rounded up);
    ``differ``: where not, and how (:func:`parting`); ``fallbacks``."""
    same, differ = [], []
    for label, (a, b) in pairs.items():
        apart = postures_apart_deg(a["frame"], b["frame"])
        if a["events"] == b["events"] and apart < PARTED_DEG:
            same.append((label, at_most(apart)))
        else:
            differ.append(f"{where([label])} {parting(a, b, names)}")
    bounds: dict[str, list[str]] = {}
    for label, bound in same:
        bounds.setdefault(bound, []).append(label)
    within = ", ".join(
        f"{bound}°" + (f" {where(labels)}" if len(bounds) > 1 else "")
        for bound, labels in sorted(bounds.items(), key=lambda b: float(b[0]))
    )
    fallbacks = sum(
        run["summary"]["solver_statistics"]["ik_fallbacks"]
        for pair in pairs.values()
        for run in pair
    )
    return {
        "agree": (
            f"the same events at the same seconds "
            f"{'' if not differ else where([label for label, _ in same]) + ' '}"
            + ("(identical postures)" if within == "0°" else f"(postures within {within})")
            if same
            else "different events"
        ),
        "differ": "".join(f"; {d}" for d in differ),
        "fallbacks": "no step of either solver falls back"
        if not fallbacks
        else f"{fallbacks} steps fall back to the other solver",
    }


@cache
def solvers() -> dict[str, str]:
    """:func:`agreement` of the wall files' runs with the nullspace solver (the wall
    generator's) and with the lexicographic one."""
    found = parallel.compute(timeline, SOLVER_CASES)
    pairs = {}
    for line, stem in wall.LINES.items():
        nullspace = wall.facts(line, "whole")
        pairs[wall.LABELS[line]] = (
            {"frame": nullspace["frame"], "events": nullspace["events"], "summary": nullspace},
            found[stem, LEXICOGRAPHIC],
        )
    return agreement(pairs)


def wall_file(line: str, keys: Mapping[str, Any] | None = None) -> cp.Problem:
    """A wall file (``line``: 'horizontal', 'm25' or 'm45') with ``keys`` set."""
    return cp.load(ROOT / "problems" / f"{wall.LINES[line]}.toml", dict(keys or {}))


def along_line(p: cp.Problem, distance_m: float) -> list[float]:
    """The point ``distance_m`` down the wrist's line from its dot (negative: up) [m],
    each coordinate to 6 significant digits, as a command line would set it."""
    task = p.data["tasks"][TARGET_TASK - 1]
    elevation = math.radians(task["elevation_deg"])
    x, y, z = task["point_m"]
    point = (x + distance_m * math.cos(elevation), y, z + distance_m * math.sin(elevation))
    return [float(f"{v:.6g}") for v in point]


def target_set(target: list[float]) -> str:
    """The ``--set`` of a wrist target, as the page's commands write it."""
    return f"'tasks[{TARGET_TASK}].target_m=[{','.join(f'{v:g}' for v in target)}]'"


def landmark(p: cp.Problem, name: str) -> ca.Function:
    """q [rad] ↦ the landmark's position [m]."""
    return ca.Function(name, [p.body.q], [p.body.landmark(name)])


def at_limit(p: cp.Problem, posture_deg: Mapping[str, float], dof: str, joint: str) -> str:
    """'the elbow at its 150° limit', or 'the elbow at 120°' when it is not at one."""
    i = p.body.index[dof]
    for bound in (p.body.lower[i], p.body.upper[i]):
        if abs(posture_deg[dof] - math.degrees(bound)) < AT_LIMIT_DEG:
            return f"{joint} at its {arm_figures.minus(math.degrees(bound), 0)}° limit"
    return f"{joint} at {arm_figures.minus(posture_deg[dof], 0)}°"


@cache
def reach() -> dict[str, Any]:
    """Where the paper's recoveries lie on the standing body: the right arm's ``reach_m``
    (the wrist's distance from the shoulder, the elbow straight), the dot's
    ``dot_height_m`` and ``dot_distance_m``; on the −25° line the paper's height
    (``paper_height_m``), how far it is ``above_dot_m`` and ``up_line_m`` (along the line),
    ``behind_m`` (behind the shoulder), the ``up_command``'s solve (lexicographic) and
    how near the wrist gets (``nearest_m``) with the elbow and lumbar spine ``at_limits``,
    and our first recovery's height ``recovery_above_m`` above the dot; on the −45° line,
    ``down``: the shoulder flexors' load [%MVC] and strength [N·m] at the dot and
    :data:`DOWN_M` down the line, and the ``down_command`` of the last."""
    m25 = wall_file("m25")
    arm = wall.reach()
    task = m25.data["tasks"][TARGET_TASK - 1]
    up = (wall.PAPER_HEIGHT_M - task["point_m"][2]) / math.sin(-math.radians(task["elevation_deg"]))
    target = along_line(m25, -up)
    target[2] = wall.PAPER_HEIGHT_M
    target = [float(f"{v:.3g}") for v in target]
    answer = cp.solve(wall_file("m25", {f"tasks[{TARGET_TASK}].target_m": target}), "lexicographic")
    reached = np.array(landmark(m25, "wrist_r")(answer.torques.q)).ravel()
    shoulder = np.array(landmark(m25, "shoulder_r")(m25.posture)).ravel()
    posture = answer.posture_deg
    lines = wall.every_line()
    m45 = wall_file("m45")
    down = {0.0: lines["m45"]["start"]["groups"][SHOULDER]}
    for d in DOWN_M:
        keys = {f"tasks[{TARGET_TASK}].target_m": along_line(m45, d)}
        down[d] = cp.solve(wall_file("m45", keys)).to_frame().set_index("name").loc[SHOULDER]
    return arm | {
        "stature_m": m25.data["body"]["stature_m"],
        "up_line_m": up,
        "behind_m": shoulder[0] - target[0],
        "up_command": f"casadi-posture solve problems/{wall.LINES['m25']}.toml --solver "
        f"lexicographic --set {target_set(target)}",
        "nearest_m": float(np.linalg.norm(reached - target)),
        "at_limits": at_limit(m25, posture, "elbow_flexion_r", "the elbow")
        + ", "
        + at_limit(m25, posture, "lumbar_flexion", "the lumbar spine"),
        "recovery_above_m": (
            lines["m25"]["whole"]["recoveries"][0]["height_m"] - arm["dot_height_m"]
        ),
        "down_m": {i: d for i, d in enumerate(DOWN_M)},
        "down": {i: dict(down[d]) for i, d in enumerate((0.0, *DOWN_M))},
        "down_command": f"casadi-posture solve problems/{wall.LINES['m45']}.toml --set "
        f"{target_set(along_line(m45, DOWN_M[-1]))}",
    }


def span(values: pd.Series) -> str:
    """'7.4', or '16.3–16.8' (one decimal)."""
    low, high = f"{values.min():.1f}", f"{values.max():.1f}"
    return low if low == high else f"{low}–{high}"


def steps(count: int) -> str:
    """1 → 'in one step', 4 → 'over 4 steps'."""
    return "in one step" if count == 1 else f"over {count} steps"


def owners(frame: pd.DataFrame) -> Iterator[tuple[str, float, float]]:
    """Each stretch of steps one group owns the constraint: (group, first step [s], the
    step it is released at or the run's last [s])."""
    owner = frame["constraint_owner"]
    changes = owner.ne(owner.shift())
    times = list(frame.index)
    starts = [t for t, change in zip(times, changes, strict=True) if change]
    for start, after in zip(starts, [*starts[1:], None], strict=True):
        if isinstance(owner[start], str):
            yield owner[start], start, times[-1] if after is None else after


def stretch(frame: pd.DataFrame, group: str, on_s: float, off_s: float) -> dict[str, Any]:
    """One group's ownership of the constraint from ``on_s`` to its release at ``off_s``
    [s]. The postures its constraint chose are those of the steps after ``on_s`` up to
    ``off_s`` (a step's posture follows the previous step's owner); the adjustment has
    settled at ``settled_s``, the last of them at which the owner's load fell by more than
    :data:`SETTLING_PCT` (else the first). ``steps`` (how many steps it took, as text),
    ``load`` (each followed group's load from ``settled_s`` to the release [%MVC], as a
    range) and ``fatigue_max`` (over every step it chose)."""
    owned = frame.loc[on_s:off_s]
    chosen = owned.iloc[1:]
    load = owned[f"load_{group}_pct_mvc"]
    falls = load.index[(-load.diff() > SETTLING_PCT).to_numpy()]
    settled = falls[-1] if len(falls) else chosen.index[0]
    after = chosen.loc[settled:]
    return {
        "on_s": on_s,
        "off_s": off_s,
        "held_s": off_s - on_s,
        "settled_s": settled,
        "steps": steps(len(chosen.loc[:settled])),
        "load": {g: span(after[f"load_{g}_pct_mvc"]) for g in wall.GROUPS},
        "fatigue_max": {g: chosen[f"fatigue_{g}"].max() for g in wall.GROUPS},
    }


@cache
def whole_m45() -> dict[str, Any]:
    """The −45° line's whole-body run, stretch by stretch of the constraint's owners:
    ``owned`` (:func:`stretch` of each), the elbow flexors' ``again_s`` (their second
    time at the threshold [s]), their ``final`` and ``max`` fatigue, and how long the wrist
    was held (``held_min``: the whole run, else the generator fails)."""
    f = wall.facts("m45", "whole")
    frame = f["frame"]
    owned = [stretch(frame, *o) for o in owners(frame)]
    back = frame.loc[owned[0]["off_s"] :].iloc[1]
    for g in wall.GROUPS:
        start = frame.iloc[0][f"load_{g}_pct_mvc"]
        if abs(back[f"load_{g}_pct_mvc"] - start) > 0.05:
            raise ValueError(f"after the first recovery the {g} carry {back[f'load_{g}_pct_mvc']}")
    if f["lost_s"] is not None:
        raise ValueError(f"the −45° whole-body hold is lost at {f['lost_s']} s")
    again = [t for t, kind, g in f["events"] if kind == "fatigue_threshold" and g == ELBOW]
    return {
        "owned": dict(enumerate(owned)),
        "again_s": again[1],
        "final": f["final_fatigue"][ELBOW],
        "max": max(h["max_fatigue"] for h in f["half_joints"] if h["half_joint"] == ELBOW),
        "held_min": f["duration_s"] / 60,
    }


def signed(value_deg: float) -> str:
    """'−80', '+80'."""
    return f"{value_deg:+.0f}".replace("-", "−")


@cache
def limits() -> dict[str, str]:
    """The standing body's limits [deg] the paper's law drives it to: the right forearm's
    pronation (``pronation``: lower, upper), the lumbar spine's extension and the knees'."""
    body = wall_file("horizontal").body
    deg = {
        d: [math.degrees(b[body.index[d]]) for b in (body.lower, body.upper)] for d in body.index
    }
    return {
        "pronation": [signed(v) for v in deg["forearm_pronation_r"]],
        "lumbar": arm_figures.minus(deg["lumbar_flexion"][0], 0),
        "knee": arm_figures.minus(deg["knee_flexion_r"][0], 0),
    }


@cache
def strategies() -> dict[str, str]:
    """The paper's law with the constraint alone, active against passive, on every line:
    ``cases`` (the goal cases its steps used, as text: cases 1.x are those with at most
    one slope of the active torque, where both strategies give the same goal) and
    ``runs`` (how the active and passive runs compare)."""
    runs = {
        line: (wall.facts(line, "paper0"), wall.facts(line, "paper0_passive"))
        for line in wall.LINES
    }
    cases = dict.fromkeys(c for a, _ in runs.values() for c in goal_cases(a["frame"]))
    apart = max(postures_apart_deg(a["frame"], b["frame"]) for a, b in runs.values())
    differ = [wall.LABELS[line] for line, (a, b) in runs.items() if a["events"] != b["events"]]
    if differ:
        compared = f"different {on_lines(differ)}"
    elif apart == 0:
        compared = "identical on all three lines"
    else:
        compared = f"the same events, postures within {at_most(apart)}°, on all three lines"
    return {
        "cases": f"in case {listed(list(cases)).replace(' and ', ' or ')} (at most one slope) "
        "on every step"
        if all(c.startswith("1.") for c in cases)
        else f"in cases {listed(list(cases))}",
        "runs": compared,
    }


def frontal_lower_deg() -> str:
    """The frontal elbow file's lower elbow limit [deg], with a typographic minus."""
    p = cp.load(ROOT / "problems" / "frontal_elbow.toml")
    return arm_figures.minus(math.degrees(p.body.lower[p.body.index["elbow_flexion"]]), 0)


class Lazy(dict):
    """The values of a template, each made the first time the template names it."""

    def __init__(self, makers: Mapping[str, Callable[[], Any]]) -> None:
        super().__init__()
        self.makers = makers

    def __missing__(self, key: str) -> Any:
        self[key] = self.makers[key]()
        return self[key]


def values(region: Region, session: Session) -> Mapping[str, Any]:
    """The values the page's templates name: the wall generator's by line (``horizontal``,
    ``m25``, ``m45``), ``solvers``, ``reach``, ``whole_m45``, ``limits``, ``workplaces``,
    ``strategies``, the 2-DOF arm's ``shoulder_height_m`` [m] and ``frontal_lower_deg``."""
    makers: dict[str, Callable[[], Any]] = {
        line: (lambda line=line: wall.every_line()[line]) for line in wall.LINES
    }
    return Lazy(
        makers
        | {
            "solvers": solvers,
            "reach": reach,
            "whole_m45": whole_m45,
            "limits": limits,
            "workplaces": workplaces,
            "frontal_lower_deg": frontal_lower_deg,
            "strategies": strategies,
            "shoulder_height_m": lambda: paper_arm.SHOULDER_HEIGHT_M,
        }
    )


#: The shipped workplace problems by the names the templates use.
WORKPLACES = {
    "shelf": "standing_shelf_box",
    "drill": "standing_overhead_drill",
    "seated": "seated_assembly",
}
WHOLE_BODY = (("fatigue.adjustment", "whole_body"),)
#: Each workplace as shipped and with the lexicographic solver; the drill under the
#: whole-body adjustment.
WORKPLACE_CASES = [(stem, keys) for stem in WORKPLACES.values() for keys in ((), LEXICOGRAPHIC)]
WORKPLACE_CASES.append((WORKPLACES["drill"], WHOLE_BODY))
#: A joint moving more than this in a step [deg] moves (the IK's last digits aside).
MOVING_DEG = 0.01
#: The right shoulder's groups the rows follow.
FLEXORS, EXTERNAL_ROTATORS = "shoulder_flexors_r", "shoulder_external_rotators_r"


def groups(summary: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The summary's half-joints by name."""
    return {h["half_joint"]: h for h in summary["half_joints"]}


def goal_cases(frame: pd.DataFrame) -> list[str]:
    """The goal cases of the paper's law over a run, each once, in the order first used."""
    return list(dict.fromkeys(str(c).split(" ")[0] for c in frame["goal_case"].dropna()))


def held(summary: dict[str, Any]) -> str:
    """'the task is held the whole 20 minutes' or 'the right shoulder flexors are exhausted
    at 41 s'."""
    lost = summary["task"]["lost"]
    if lost is None:
        return f"the task is held the whole {summary['duration_s'] / 60:.0f} minutes"
    base, _, side = lost["half_joint"].rpartition("_")
    name = {"r": f"right {base}", "l": f"left {base}"}.get(side, lost["half_joint"])
    return f"the {name.replace('_', ' ')} are exhausted at {lost['time_s']:.0f} s"


def moving(frame: pd.DataFrame) -> pd.DataFrame:
    """The steps at which some joint moves more than :data:`MOVING_DEG`."""
    angles = [c for c in frame.columns if c.endswith("_deg") and c != "goal_angle_deg"]
    return frame[(frame[angles].diff().abs().max(axis=1) > MOVING_DEG).to_numpy()]


def still(frame: pd.DataFrame, from_s: float) -> bool:
    """Whether no joint moves (:func:`moving`) after ``from_s`` [s]."""
    return moving(frame.loc[from_s:]).empty


def shelf(run: dict[str, Any], p: cp.Problem) -> dict[str, Any]:
    """The shelf row: the box's ``mass_kg``, the shelf's ``height_m`` and ``ahead_m``, the
    start posture (``start``, by DOF [deg]), ``mirror`` (how far paired joints are from
    their mirror [deg], a bound), the flexors' start ``load`` [%MVC] and ``endurance``
    [min] (``who``: both shoulders' when the left's are the same), ``case`` and ``why`` of the goal,
    whether the posture ``stays``, the end's asymmetry (``apart_deg``) and plausibility
    flags, and ``held`` (:func:`held`)."""
    s, frame = run["summary"], run["frame"]
    right, left = groups(s)[FLEXORS], groups(s)["shoulder_flexors_l"]
    postures = {q["label"]: q for q in s["plausibility"]["postures"]}
    case = frame["goal_case"].dropna().iloc[0]
    on = next(t for t, kind, _ in run["events"] if kind == "constraint_on")
    return {
        "mass_kg": sum(load["mass_kg"] for load in p.data["loads"]),
        "height_m": p.data["tasks"][2]["target_m"][2],
        "ahead_m": p.data["tasks"][2]["target_m"][0],
        "start": {
            c.removesuffix("_deg"): v for c, v in frame.iloc[0].items() if c.endswith("_deg")
        },
        "mirror": at_most(postures["start"]["asymmetry_deg"]),
        "load": right["initial_load_pct_mvc"],
        "endurance": right["initial_endurance_min"],
        "who": "both shoulders' flexors"
        if abs(right["initial_load_pct_mvc"] - left["initial_load_pct_mvc"]) < 0.05
        else "the right shoulder's flexors",
        "threshold_s": right["first_fatigue_threshold_s"],
        "case": case.split(" ")[0],
        "why": case.partition("(")[2].rstrip(")"),
        "stays": "the posture stays" if still(frame, on) else "the posture still moves",
        "apart_deg": postures["end"]["asymmetry_deg"],
        "flags": "; ".join(s["plausibility"]["flags"]) or "nothing flagged",
        "held": held(s),
    }


def drill(run: dict[str, Any], whole: dict[str, Any], p: cp.Problem) -> dict[str, Any]:
    """The drill row: the drill's ``mass_kg`` and ``height_m``; the flexors' start
    ``load`` [%MVC] and ``endurance`` [min], their ``threshold_s``; how many steps the
    paper's law moves the arm (``moves``, with ``move_cases``), where it stops
    (``flexion_deg``, ``stop_load`` [%MVC]), the case that keeps it (``stop_case``,
    ``why``), ``held``; the trunk's ``turn_deg`` at the start; the whole-body run's
    ``recoveries_s`` and ``whole_held``."""
    s, frame = run["summary"], run["frame"]
    on = next(t for t, kind, _ in run["events"] if kind == "constraint_on")
    moves = moving(frame.loc[on:])
    last = moves.index[-1]
    stop_case = frame.loc[last:, "goal_case"].dropna().iloc[-1]
    flexors = groups(s)[FLEXORS]
    return {
        "mass_kg": sum(load["mass_kg"] for load in p.data["loads"]),
        "height_m": p.data["tasks"][2]["target_m"][2],
        "load": flexors["initial_load_pct_mvc"],
        "endurance": flexors["initial_endurance_min"],
        "threshold_s": flexors["first_fatigue_threshold_s"],
        "moves": len(moves),
        "move_cases": listed(goal_cases(moves)),
        "flexion_deg": frame.loc[last, "shoulder_flexion_r_deg"],
        "stop_load": frame.loc[last, f"load_{FLEXORS}_pct_mvc"],
        "stop_case": stop_case.split(" ")[0],
        "why": stop_case.partition("(")[2].rstrip(")"),
        "stays": "the posture stays" if still(frame, last) else "the posture still moves",
        "held": held(s),
        "turn_deg": abs(frame.iloc[0]["lumbar_rotation_deg"]),
        "recoveries_s": listed(
            [f"{p['time_s']:.0f}" for p in whole["summary"]["recovery_postures"]]
        ),
        "whole_held": held(whole["summary"]),
    }


def seated(run: dict[str, Any], p: cp.Problem) -> dict[str, Any]:
    """The seated row: the body's ``hip_height_m``, the part's ``mass_kg``, ``ahead_m`` and
    ``height_m``; the flexors' start ``load`` [%MVC], ``endurance`` [min] and
    ``threshold_s``; over the first constraint, the shoulder's least flexion
    (``flexion_min_deg``), its abduction (``abduction_deg``) and the trunk's turn
    (``turn_deg``) where it stays at the recovery, the abduction's largest
    (``abduction_max_deg``), the ``cases``; the external rotators' largest load [%MVC]
    and fatigue; the ``recoveries_s``, the ``gap_s`` from the first recovery to the next
    threshold, ``cycles``, ``held``; the lumbar extension at the start (``extension_deg``)
    and the plausibility report's threshold (``flagged_deg``)."""
    s, frame = run["summary"], run["frame"]
    on, off = next(owners(frame))[1:]
    first = frame.loc[on:off]
    recovery = s["recovery_postures"][0]["posture_deg"]
    flexors = groups(s)[FLEXORS]
    times = [t for t, kind, g in run["events"] if kind == "fatigue_threshold" and g == FLEXORS]
    trunk = parameters.load("plausibility")["plausibility.trunk_extension"].value
    return {
        "hip_height_m": p.data["body"]["hip_height_m"],
        "mass_kg": sum(load["mass_kg"] for load in p.data["loads"]),
        "ahead_m": p.data["tasks"][0]["target_m"][0],
        "height_m": p.data["tasks"][0]["target_m"][2],
        "load": flexors["initial_load_pct_mvc"],
        "endurance": flexors["initial_endurance_min"],
        "threshold_s": flexors["first_fatigue_threshold_s"],
        "flexion_min_deg": arm_figures.minus(first["shoulder_flexion_r_deg"].min(), 0),
        "abduction_deg": recovery["shoulder_abduction_r"],
        "turn_deg": first["lumbar_rotation_deg"].abs().max(),
        "abduction_max_deg": first["shoulder_abduction_r_deg"].max(),
        "cases": listed(goal_cases(first)),
        "rotators_max": frame[f"load_{EXTERNAL_ROTATORS}_pct_mvc"].max(),
        "rotators_fatigue": groups(s)[EXTERNAL_ROTATORS]["max_fatigue"],
        "recoveries_s": listed([f"{q['time_s']:.0f}" for q in s["recovery_postures"]]),
        "gap_s": times[1] - off,
        "again": frame.loc[times[1], f"load_{FLEXORS}_pct_mvc"],
        "cycles": s["fatigue_recovery_cycles"],
        "held": held(s),
        "extension_deg": -frame.iloc[0]["lumbar_flexion_deg"],
        "flagged_deg": trunk,
    }


@cache
def workplaces() -> dict[str, Any]:
    """The workplace table's values: ``solvers`` (:func:`agreement` of the nullspace and
    lexicographic runs of every workplace) and each row's (:func:`shelf`, :func:`drill`,
    :func:`seated`)."""
    runs = parallel.compute(timeline, WORKPLACE_CASES)
    pairs = {
        f"`{stem}.toml`": (runs[stem, ()], runs[stem, LEXICOGRAPHIC])
        for stem in WORKPLACES.values()
    }
    shipped = {name: runs[stem, ()] for name, stem in WORKPLACES.items()}
    files = {name: cp.load(ROOT / "problems" / f"{stem}.toml") for name, stem in WORKPLACES.items()}
    return {
        "solvers": agreement(pairs, lambda labels: f"on {listed(labels)}"),
        "shelf": shelf(shipped["shelf"], files["shelf"]),
        "drill": drill(shipped["drill"], runs[WORKPLACES["drill"], WHOLE_BODY], files["drill"]),
        "seated": seated(shipped["seated"], files["seated"]),
    }
