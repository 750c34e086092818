"""The paper's experiments on the 2-DOF arm (docs/scenarios.md): the holding experiments
under every recovery law, and the numbers that explain them."""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from functools import cache
from typing import Any

import casadi_posture as cp

from . import parallel
from .regions import Region
from .session import ROOT, Session

#: The holding lines: label in the tables, elevation [deg].
LINES = (("horizontal", 0.0), ("−25°", -25.0), ("−45°", -45.0))
LAWS = ("threshold", "continuous", "3cc_r")
KEEP_LEVELS = (0, 1)
STRATEGIES = ("active", "passive")
#: The arm files whose figures rely on the constant shoulder-flexor strength they keep.
CURVE_FILES = ("holding_m45", "line_plane_hysteresis", "strategy_shoulder_limit")

#: The shoulder's height above the floor [m] that turns the arm's heights (origin at the
#: shoulder) into the paper's: an estimate for the reference man.
SHOULDER_HEIGHT_M = 1.42
#: Two recoveries closer than this [m] in height and distance are at one position.
SAME_POSITION_M = 0.005
#: A line residual [m] above this at a recovery: the constraint broke the line there.
ON_LINE_M = 1e-4


def problem(name: str, keys: dict[str, Any] | None = None) -> cp.Problem:
    """A shipped problem with ``keys`` set."""
    return cp.load(ROOT / "problems" / f"{name}.toml", keys or {})


def holding(elevation_deg: float, law: str, keep: int, strategy: str = "active") -> cp.Simulation:
    """The −45° holding file with its line at ``elevation_deg``, simulated."""
    keys = {
        "tasks[0].elevation_deg": elevation_deg,
        "fatigue.recovery_law": law,
        "fatigue.keep_levels": keep,
        "fatigue.strategy": strategy,
    }
    return cp.simulate(problem("holding_m45", keys))


def case_facts(elevation_deg: float, law: str, keep: int, strategy: str) -> dict[str, Any]:
    """What the documents say of one holding case (in a form that pickles): its
    ``cycles``, ``recovery`` and ``lost`` texts, ``postures`` (time [s], shoulder and
    elbow angles [deg] at every step) and the elbow ``end`` (:func:`at_the_end`)."""
    run = holding(elevation_deg, law, keep, strategy)
    frame = run.to_frame()
    return {
        "cycles": run.summary()["fatigue_recovery_cycles"],
        "first_s": (run.summary()["first_to_fatigue"] or {}).get("time_s"),
        "recovery": recovery_text(run),
        "lost": lost_text(run),
        "postures": frame[["time_s", "shoulder_flexion_deg", "elbow_flexion_deg"]].to_numpy(),
        "end": at_the_end(run),
        "t0": run.summary()["recovery_law"].get("load_threshold_pct_mvc"),
    }


def every_case() -> list[tuple[float, str, int, str]]:
    """Every case of the table, with each strategy: (elevation, law, kept levels, strategy)."""
    return [(e, law, keep, s) for _, e, keep, law in cases() for s in STRATEGIES]


def prefetch() -> None:
    """Start every case in the background."""
    parallel.submit(case_facts, every_case())


@cache
def all_cases() -> dict[tuple[float, str, int, str], dict[str, Any]]:
    """:func:`case_facts` of every case of the table, with each strategy."""
    return parallel.compute(case_facts, every_case())


def group(half_joint: str | None) -> str:
    """'shoulder_flexors' → 'shoulder flexors'."""
    return (half_joint or "").replace("_", " ")


def recovery_text(run: cp.Simulation) -> str:
    """The recovery positions: wrist height above the floor and distance from the
    shoulder, when, and how far the line was broken there."""
    frame = run.to_frame().set_index("time_s")
    groups: list[list[tuple[float, float, float, float]]] = []
    for posture in run.summary()["recovery_postures"]:
        t = posture["time_s"]
        x, z = frame.at[t, "wrist_x_m"], frame.at[t, "wrist_z_m"]
        found = (t, SHOULDER_HEIGHT_M + z, math.hypot(x, z), frame.at[t, "residual_level1_m"])
        for g in groups:
            if abs(g[0][1] - found[1]) < SAME_POSITION_M and abs(g[0][2] - found[2]) < (
                SAME_POSITION_M
            ):
                g.append(found)
                break
        else:
            groups.append([found])
    parts = []
    for g in groups:
        t, height, distance, off = g[0]
        again = f"; the same at {', '.join(f'{r[0]:.0f}' for r in g[1:])} s" if g[1:] else ""
        broken = f"; line broken by {off:.3f} m" if off > ON_LINE_M else ""
        parts.append(f"{height:.2f} m, {distance:.2f} m ({t:.0f} s{again}{broken})")
    return "; ".join(parts) or "—"


def lost_text(run: cp.Simulation) -> str:
    """When the task was lost and to which group, or that it was held."""
    task = run.summary()["task"]
    if task["lost"] is None:
        return f"held {task['held_s']:.0f} s"
    return f"{task['lost']['time_s']:.0f} s, {group(task['lost']['half_joint'])}"


def cases() -> Iterator[tuple[str, float, int, str]]:
    """Every case of the recovery-law table, in its order."""
    for label, elevation in LINES:
        for keep in KEEP_LEVELS:
            for law in LAWS:
                yield label, elevation, keep, law


def laws_table(region: Region, session: Session) -> str:
    """The recovery-law table of docs/scenarios.md."""
    rows = [
        "| line | keep_levels | recovery law | cycles | first recovery: wrist height, "
        "distance from the shoulder | task lost |",
        "|---|---|---|---|---|---|",
    ]
    for label, elevation, keep, law in cases():
        case = all_cases()[elevation, law, keep, "active"]
        cells = (label, str(keep), f"`{law}`", str(case["cycles"]), case["recovery"], case["lost"])
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def identical(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two cases give the same postures at the same steps."""
    x, y = a["postures"], b["postures"]
    return x.shape == y.shape and bool(abs(x - y).max() < 1e-9)


def at_the_end(run: cp.Simulation) -> dict[str, float]:
    """The elbow at the end of a run: angle [deg], its torques [N·m] and the elbow
    flexors' load [%MVC], with gravity alone and with the passive torque."""
    last = run.to_frame().iloc[-1]
    strength = start_loads(run.result.problem)["elbow_flexors"]["strength_Nm"]
    external = -last["tau_external_elbow_flexion_Nm"]
    return {
        "elbow_deg": last["elbow_flexion_deg"],
        "passive_Nm": -last["tau_passive_elbow_flexion_Nm"],
        "external_Nm": external,
        "active_Nm": last["tau_active_elbow_flexion_Nm"],
        "gravity_pct": 100 * external / strength,
        "load_pct": last["load_elbow_flexors_pct_mvc"],
        "lost_s": run.summary()["task"]["held_s"],
    }


def start_loads(p: cp.Problem) -> dict[str, dict[str, float]]:
    """Each group's strength and torque [N·m] and load [%MVC] at the problem's start
    posture."""
    frame = cp.solve(p).to_frame()
    return {
        row["name"]: {
            "strength_Nm": row["strength_Nm"],
            "torque_Nm": row["torque_Nm"],
            "load_pct": row["load_pct_mvc"],
        }
        for _, row in frame.iterrows()
    }


def with_the_curve(name: str) -> cp.Simulation:
    """A shipped arm file simulated with the shoulder flexors' default strength curve
    instead of the constant strength the file keeps."""
    base = problem(name)
    data = copy.deepcopy(base.data)
    del data["body"]["half_joints"]["shoulder_flexors"]
    if not data["body"]["half_joints"]:
        del data["body"]["half_joints"]
    return cp.simulate(cp.from_dict(data, str(base.path), {}))


def first(run: cp.Simulation) -> str:
    """Which group reaches the fatigue threshold first, and when; or that none does."""
    found = run.summary()["first_to_fatigue"]
    if found is None:
        return "no group reaches the fatigue threshold"
    return (
        f"the {group(found['half_joint'])} reach the threshold first (at {found['time_s']:.0f} s)"
    )


def values(region: Region, session: Session) -> dict[str, Any]:
    """:func:`explanation` (computed once per run of the generators)."""
    return explanation()


@cache
def explanation() -> dict[str, Any]:
    """The numbers of the explanations under the table: ``start`` (the groups at the
    preferred dot), ``shoulder_threshold_s``, ``t0`` (the threshold law's T_0 [%MVC]),
    ``end`` by line label (:func:`at_the_end` of the paper's constraint with the
    ``threshold`` law), ``strategies`` (whether the active and passive runs of every case
    are identical), ``elbow_limit_deg``, ``hysteresis`` (the line-plane file's groups at
    the start) and ``curve`` (what the strength curve would change)."""
    m45 = problem("holding_m45")
    lp = problem("line_plane_hysteresis")
    found = all_cases()
    differ = [
        k for k in found if k[3] == "active" and not identical(found[k], found[(*k[:3], "passive")])
    ]
    return {
        "start": start_loads(m45),
        "shoulder_threshold_s": found[-45.0, "threshold", 0, "active"]["first_s"],
        "t0": found[-45.0, "threshold", 0, "active"]["t0"],
        "end": {label: found[e, "threshold", 0, "active"]["end"] for label, e in LINES},
        "strategies": "identical runs in every one of these cases"
        if not differ
        else f"different runs in {len(differ)} of these cases",
        "elbow_limit_deg": math.degrees(m45.body.upper[m45.body.index["elbow_flexion"]]),
        "hysteresis": start_loads(lp),
        "curve": {name: first(with_the_curve(name)) for name in CURVE_FILES},
    }
