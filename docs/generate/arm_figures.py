"""The paper's figures on the 2-DOF arm and the frontal elbow (docs/scenarios.md, the
first table): each shipped file simulated as it is, or with the other strategy, and the
numbers the table's row says of it."""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import pandas as pd

import casadi_posture as cp

from . import paper_arm, parallel
from .regions import Region
from .session import ROOT, Session

#: Every run: the file's stem and the keys set on it (as pairs, so that a case hashes).
CASES: tuple[tuple[str, tuple[tuple[str, Any], ...]], ...] = (
    ("line_plane_hysteresis", ()),
    ("holding_m25", ()),
    ("holding_horizontal", ()),
    ("holding_m45", ()),
    ("strategy_shoulder_limit", ()),
    ("strategy_extensors", ()),
    ("strategy_extensors", (("fatigue.strategy", "passive"),)),
    ("strategy_frontal_elbow", ()),
    ("strategy_frontal_elbow", (("fatigue.strategy", "passive"),)),
)
#: A joint within this of its limit [deg] is at it (the shoulder nears its 0° limit
#: geometrically, a little less each step).
AT_LIMIT_DEG = 0.01


def load(name: str, keys: tuple[tuple[str, Any], ...] = ()) -> cp.Problem:
    """A shipped problem with ``keys`` set."""
    return cp.load(ROOT / "problems" / f"{name}.toml", dict(keys))


def run(name: str, keys: tuple[tuple[str, Any], ...]) -> tuple[dict[str, Any], pd.DataFrame]:
    """One case simulated: its summary and timeline (in a form that pickles)."""
    simulation = cp.simulate(load(name, keys))
    return simulation.summary(), simulation.to_frame()


def prefetch() -> None:
    """Start every run in the background."""
    parallel.submit(run, CASES)


def minus(value: float, digits: int = 1) -> str:
    """A signed angle or length with the typographic minus: '−28.9'."""
    return f"{value:.{digits}f}".replace("-", "−")


def group(half_joint: str | None) -> str:
    """'elbow_flexors' → 'elbow flexors'."""
    return (half_joint or "").replace("_", " ")


def cases(frame: pd.DataFrame) -> str:
    """The goal cases of Table 1 the run used, in the order it first used them."""
    used = [str(c) for c in frame["goal_case"].dropna() if str(c)]
    return " then ".join(dict.fromkeys(used))


def initial_load(summary: dict[str, Any], half_joint: str) -> float:
    """A group's load at the start [%MVC]."""
    return next(h for h in summary["half_joints"] if h["half_joint"] == half_joint)[
        "initial_load_pct_mvc"
    ]


def recovered(count: int) -> str:
    """'no recovery', '1 recovery', '2 recoveries'."""
    return "no recovery" if not count else f"{count} recover{'y' if count == 1 else 'ies'}"


def holding(summary: dict[str, Any], frame: pd.DataFrame) -> dict[str, Any]:
    """A holding run: the elbow flexors' start load, when and to whom the task was lost,
    how far the line was broken [m] and the recoveries."""
    lost = summary["task"]["lost"]
    return {
        "elbow_start_pct": initial_load(summary, "elbow_flexors"),
        "lost_s": lost["time_s"] if lost else None,
        "lost_group": group(lost["half_joint"]) if lost else None,
        "line_broken_m": frame["residual_level1_m"].max(),
        "recovered": recovered(len(summary["recovery_postures"])),
    }


def fig3() -> str:
    """The zeros of the elbow's active torque (``curve``): '1.8°, 90.0° (forearm
    vertical) and 147.7°'."""
    problem = load("frontal_elbow")
    zeros = [
        f"{math.degrees(z.angle):.1f}°"
        + (" (forearm vertical)" if z.kind.startswith("active") else "")
        for z in cp.curve(problem, "elbow_flexion").zeros
    ]
    return ", ".join(zeros[:-1]) + " and " + zeros[-1]


def values(region: Region, session: Session) -> dict[str, Any]:
    """:func:`figures` (computed once per run of the generators)."""
    return figures()


@cache
def figures() -> dict[str, Any]:
    """The numbers of the table's rows, by figure."""
    found = parallel.compute(run, CASES)
    lp_s, lp = found["line_plane_hysteresis", ()]
    recovery = lp_s["recovery_postures"][0]
    sl_s, sl = found["strategy_shoulder_limit", ()]
    sl_body = load("strategy_shoulder_limit").body
    sl_limit = math.degrees(sl_body.lower[sl_body.index["shoulder_flexion"]])
    at_limit = sl[(sl["shoulder_flexion_deg"] - sl_limit).abs() < AT_LIMIT_DEG].iloc[0]
    ex_s, ex = found["strategy_extensors", ()]
    _, exp = found["strategy_extensors", (("fatigue.strategy", "passive"),)]
    angles = ["shoulder_flexion_deg", "elbow_flexion_deg"]
    ex_body = load("strategy_extensors").body
    fe_s, fe = found["strategy_frontal_elbow", ()]
    fep_s, fep = found["strategy_frontal_elbow", (("fatigue.strategy", "passive"),)]
    return {
        "fig3_zeros": fig3(),
        "lp": {
            "first_s": lp_s["first_to_fatigue"]["time_s"],
            "slide_m": -lp["wrist_along_line_m"].min(),
            "line_m": paper_arm.sci(lp["residual_level1_m"].max()),
            "plane_m": lp["residual_level2_m"].max(),
            "recovery_s": recovery["time_s"],
            "shoulder_deg": minus(recovery["posture_deg"]["shoulder_flexion"]),
            "elbow_deg": recovery["posture_deg"]["elbow_flexion"],
            "cycles": lp_s["fatigue_recovery_cycles"],
            "duration_min": lp_s["duration_s"] / 60,
        },
        "m25": holding(*found["holding_m25", ()]),
        "horizontal": holding(*found["holding_horizontal", ()]),
        "m45": holding(*found["holding_m45", ()]),
        "reach_m": paper_arm.reach_m(load("holding_horizontal")),
        "sl": {
            "start_Nm": sl["tau_active_shoulder_flexion_Nm"].iloc[0],
            "start_pct": sl["load_shoulder_flexors_pct_mvc"].iloc[0],
            "limit_deg": sl_limit,
            "limit_s": at_limit["time_s"],
            "limit_active_Nm": at_limit["tau_active_shoulder_flexion_Nm"],
            "limit_passive_Nm": at_limit["tau_passive_shoulder_flexion_Nm"],
            "recovery_s": sl_s["recovery_postures"][0]["time_s"],
        },
        "ex": {
            "start_pct": initial_load(ex_s, "elbow_extensors"),
            "first_group": group(ex_s["first_to_fatigue"]["half_joint"]),
            "first_s": ex_s["first_to_fatigue"]["time_s"],
            "cases": cases(ex),
            "r_min": ex_s["r_min"],
            "strategies": "identical"
            if ex[angles].shape == exp[angles].shape
            and (ex[angles] - exp[angles]).abs().to_numpy().max() < 1e-9
            else "different",
            "elbow_max_deg": ex["elbow_flexion_deg"].max(),
            "elbow_limit_deg": math.degrees(ex_body.upper[ex_body.index["elbow_flexion"]]),
            "recovery_s": ex_s["recovery_postures"][0]["time_s"],
        },
        "fe": {
            "mass_kg": load("strategy_frontal_elbow").data["loads"][0]["mass_kg"],
            "start_pct": initial_load(fe_s, "elbow_flexors"),
            "active_deg": fe["elbow_flexion_deg"].max(),
            "active_cases": cases(fe),
            "recovery_s": fe_s["recovery_postures"][0]["time_s"],
            "passive_deg": minus(fep["elbow_flexion_deg"].min()),
            "passive_cases": cases(fep),
            "passive_max_fatigue": fep["fatigue_elbow_flexors"].max(),
            "passive_end_fatigue": fep["fatigue_elbow_flexors"].iloc[-1],
            "passive_recovered": recovered(len(fep_s["recovery_postures"])),
            "end_s": fep["time_s"].iloc[-1],
        },
    }
