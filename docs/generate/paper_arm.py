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
#: The load threshold T_0 [%MVC] the documents try in place of the law's (no source
#: supports it).
T0_ALTERNATIVE = 25.0
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
    ``cycles``, ``recovery`` and ``lost`` texts, ``positions``
    (:func:`recovery_positions`), ``line_max_m`` (the line's largest residual [m]),
    ``postures`` (time [s], shoulder and
    elbow angles [deg] at every step) and the elbow ``end`` (:func:`at_the_end`)."""
    run = holding(elevation_deg, law, keep, strategy)
    frame = run.to_frame()
    positions = recovery_positions(run)
    return {
        "cycles": run.summary()["fatigue_recovery_cycles"],
        "first_s": (run.summary()["first_to_fatigue"] or {}).get("time_s"),
        "recovery": recovery_text(positions),
        "positions": positions,
        "line_max_m": frame["residual_level1_m"].max(),
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


def recovery_positions(run: cp.Simulation) -> list[dict[str, Any]]:
    """The recovery positions, recoveries at one position together: the wrist's
    ``height_m`` above the floor and ``distance_m`` from the shoulder, ``times_s`` and
    ``broken_m``, how far the line was broken at the first [m]."""
    frame = run.to_frame().set_index("time_s")
    groups: list[dict[str, Any]] = []
    for posture in run.summary()["recovery_postures"]:
        t = posture["time_s"]
        x, z = frame.at[t, "wrist_x_m"], frame.at[t, "wrist_z_m"]
        height, distance = SHOULDER_HEIGHT_M + z, math.hypot(x, z)
        for g in groups:
            if (
                abs(g["height_m"] - height) < SAME_POSITION_M
                and abs(g["distance_m"] - distance) < SAME_POSITION_M
            ):
                g["times_s"].append(t)
                break
        else:
            groups.append(
                {
                    "height_m": height,
                    "distance_m": distance,
                    "times_s": [t],
                    "broken_m": frame.at[t, "residual_level1_m"],
                }
            )
    return groups


def recovery_text(positions: list[dict[str, Any]]) -> str:
    """The table's cell: each position, when, and how far the line was broken there."""
    parts = []
    for g in positions:
        first, *later = g["times_s"]
        again = f"; the same at {', '.join(f'{t:.0f}' for t in later)} s" if later else ""
        broken = f"; line broken by {g['broken_m']:.3f} m" if g["broken_m"] > ON_LINE_M else ""
        parts.append(
            f"{g['height_m']:.2f} m, {g['distance_m']:.2f} m ({first:.0f} s{again}{broken})"
        )
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


def reach_m(p: cp.Problem) -> float:
    """The arm's reach: the wrist's distance from the shoulder, the arm straight [m]."""
    marks = p.body.landmarks
    return math.dist(marks["shoulder"].position, marks["wrist"].position)


def sci(value: float) -> str:
    """``1.8e-09`` → ``'2e-9'``."""
    mantissa, exponent = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def times(count: int) -> str:
    """1 → 'once', 2 → 'twice', 3 → '3 times'."""
    return {1: "once", 2: "twice"}.get(count, f"{count} times")


def laws(found: dict[tuple[float, str, int, str], dict[str, Any]]) -> dict[str, Any]:
    """The bullets under the recovery-law table: the laws that recover at all
    (``recovering``), ``3cc_r``'s recoveries with the paper's constraint by line label
    (``times``, ``where``: at how many positions, ``height_m`` of the first, ``broken``: how
    far the line was broken there, as text), the recoveries' distances from the shoulder
    (``distances_m``: least and most [m]) and the line's largest residual when it is kept
    (``kept_line_m``)."""
    active = {k: v for k, v in found.items() if k[3] == "active"}
    recovering = sorted({k[1] for k, v in active.items() if v["cycles"]})
    by_line = {}
    for label, elevation in LINES:
        positions = active[elevation, "3cc_r", 0, "active"]["positions"]
        broken = max((g["broken_m"] for g in positions), default=0.0)
        by_line[label] = {
            "times": times(sum(len(g["times_s"]) for g in positions)),
            "where": "one position" if len(positions) == 1 else f"{len(positions)} positions",
            "height_m": positions[0]["height_m"] if positions else math.nan,
            "broken": f", though there only by breaking the line (by {broken:.3f} m)"
            if broken > ON_LINE_M
            else "",
        }
    distances = [g["distance_m"] for v in active.values() for g in v["positions"]]
    return {
        "recovering": " and ".join(f"`{law}`" for law in recovering),
        "3cc_r": by_line,
        "distances_m": (min(distances), max(distances)),
        "kept_line_m": sci(max(v["line_max_m"] for k, v in active.items() if k[2] == 1)),
    }


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
    the start), ``curve`` (what the strength curve would change), ``laws`` (:func:`laws`),
    the load's ``mass_kg``, the arm's ``reach_m`` and ``t0_25`` (the horizontal hold's
    cycles with T_0 = ``T0_ALTERNATIVE``)."""
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
        "laws": laws(found),
        "mass_kg": m45.data["loads"][0]["mass_kg"],
        "reach_m": reach_m(m45),
        "t0_25": {
            "cycles": cp.simulate(
                problem("holding_horizontal", {"fatigue.load_threshold_pct_mvc": T0_ALTERNATIVE})
            ).summary()["fatigue_recovery_cycles"],
            "t0": T0_ALTERNATIVE,
        },
    }
