"""docs/strength.md: what the measured strengths changed in the shipped answers, each
"before" reproduced by the same run with the group's earlier constant strength
(``strength.comfort_ratio`` × elbow flexion, set by ``--set``): the shoulder flexors'
curve (``strength-flexors``), the rotators and trunk extensors (``strength-rotators``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp

from . import shipped_runs, strength
from .regions import Region
from .session import ROOT, Session

#: The problems the flexors' table shows, with their labels.
FLEXOR_ROWS = {
    "wall": "`standing_wall_horizontal`",
    "shelf": "`standing_shelf_box`",
    "drill": "`standing_overhead_drill`",
    "seated": "`seated_assembly`",
}
#: The group whose strength the flexors' table follows.
FLEXORS = "shoulder_flexors_r"
#: The what-if case of docs/whatif.md the rotators' table quotes: the shelf at 1.00 m with
#: 2 kg in each hand.
SHELF_CASE = {
    "tasks[2].target_m[2]": 1.0,
    "tasks[3].target_m[2]": 1.0,
    "loads[0].mass_kg": 2,
    "loads[1].mass_kg": 2,
}


def prefetch() -> None:
    """Start the page's runs in the background."""
    shipped_runs.prefetch(
        [(n, v) for n in FLEXOR_ROWS for v in ("shipped", "constant_flexors")]
        + [("seated", "earlier_strengths")]
    )


def group_name(half_joint: str) -> str:
    """'shoulder_external_rotators_r' → 'external rotators' style: the group without side."""
    return half_joint.removesuffix("_r").removesuffix("_l").replace("_", " ")


def outcome(s: dict[str, Any]) -> str:
    """'the elbow flexors exhausted at 662 s' or 'held 30 min'."""
    lost = s["task"]["lost"]
    if lost is None:
        return f"held {s['duration_s'] / 60:.0f} min"
    return f"the {group_name(lost['half_joint'])} exhausted at {lost['time_s']:.0f} s"


def cell(s: dict[str, Any]) -> str:
    """The shoulder flexors' load at the start, their first threshold and the end."""
    flexors = {h["half_joint"]: h for h in s["half_joints"]}[FLEXORS]
    first = flexors["first_fatigue_threshold_s"]
    threshold = f"at the threshold at {first:.0f} s" if first is not None else "never tired"
    return f"{flexors['initial_load_pct_mvc']:.1f} %MVC; {threshold}; {outcome(s)}"


def span(a: float, b: float, digits: int) -> str:
    """'54–60' (the smaller first), or '92' when both round alike."""
    low, high = (f"{v:.{digits}f}" for v in sorted((a, b)))
    return low if low == high else f"{low}–{high}"


def flexors(region: Region, session: Session) -> dict[str, Any]:
    """``table``: each problem of :data:`FLEXOR_ROWS` simulated with the shoulder flexors'
    earlier constant and as shipped; ``ratio`` (the constant's ratio to elbow flexion),
    ``constant_Nm`` (it for the reference man at 30 y [N·m]), ``deg[NAME]`` (the right
    shoulder's flexion at the start [deg]), ``load_pct[NAME]`` (the load with the curve
    over the load with the constant [%]) and ``later[NAME]`` (the first threshold's time
    with the curve over with the constant); ``low_load``, ``low_later`` (the wall's and the
    seated reach's) and ``high_load`` (the shelf's and the drill's) as :func:`span`."""
    constant = strength.earlier("shoulder_flexors", "male")
    rows = [
        f"| Problem | constant ({constant:.1f} N·m for the reference man) | with the curve "
        "(as shipped) |",
        "| --- | --- | --- |",
    ]
    load_pct, later = {}, {}
    for name, label in FLEXOR_ROWS.items():
        before = shipped_runs.summary(name, "constant_flexors")
        now = shipped_runs.summary(name, "shipped")
        rows.append(f"| {label} | {cell(before)} | {cell(now)} |")
        b, n = ({h["half_joint"]: h for h in s["half_joints"]}[FLEXORS] for s in (before, now))
        load_pct[name] = 100 * n["initial_load_pct_mvc"] / b["initial_load_pct_mvc"]
        later[name] = n["first_fatigue_threshold_s"] / b["first_fatigue_threshold_s"]
    return {
        "table": "\n".join(rows),
        "ratio": strength.comfort_ratio("shoulder_flexors"),
        "constant_Nm": constant,
        "deg": {n: shipped_runs.start(n).posture_deg["shoulder_flexion_r"] for n in FLEXOR_ROWS},
        "load_pct": load_pct,
        "later": later,
        "low_load": span(load_pct["wall"], load_pct["seated"], 0),
        "low_later": span(later["wall"], later["seated"], 1),
        "high_load": span(load_pct["shelf"], load_pct["drill"], 0),
    }


def rotators(region: Region, session: Session) -> dict[str, Any]:
    """``before[man|woman][GROUP]`` and ``now[...]``: the earlier constant and today's
    strength [N·m] of the rotators and trunk extensors for de Leva's reference man and
    woman at 30 y, ``ratio[GROUP]`` the earlier ratio; ``seated``: the seated assembly
    with the earlier and today's strengths (``before``, ``now``: their summaries, with
    ``recovery_load``, the external rotators' load at the first recovery [%MVC], and
    ``groups``, the half-joints by name); ``capable``: the what-if shelf case's share
    capable [%] by variant and sex."""
    groups = shipped_runs.ROTATORS_AND_TRUNK
    people = {"man": "male", "woman": "female"}
    seated = {
        key: shipped_runs.summary("seated", variant)
        for key, variant in (("before", "earlier_strengths"), ("now", "shipped"))
    }
    return {
        "ratio": {g: strength.comfort_ratio(g) for g in groups},
        "before": {p: {g: strength.earlier(g, sex) for g in groups} for p, sex in people.items()},
        "now": {
            p: {g: strength.group_strength(g, sex, 30) for g in groups} for p, sex in people.items()
        },
        "seated": {key: with_groups(s) for key, s in seated.items()},
        "capable": {
            key: shelf_capable(variant)
            for key, variant in (("before", "earlier_strengths"), ("now", "shipped"))
        },
    }


def with_groups(s: dict[str, Any]) -> dict[str, Any]:
    """The summary with ``groups`` (its half-joints by name), ``lost_group``, ``outcome``
    (:func:`outcome`) and ``first_recovery_s`` (None without a recovery)."""
    lost = s["task"]["lost"]
    return s | {
        "groups": {h["half_joint"]: h for h in s["half_joints"]},
        "lost_group": group_name(lost["half_joint"]) if lost else None,
        "outcome": outcome(s),
        "first_recovery_s": s["recovery_postures"][0]["time_s"] if s["recovery_postures"] else None,
    }


def shelf_capable(variant: str) -> dict[str, float]:
    """The share of men and women capable [%] of the shelf hold of :data:`SHELF_CASE`."""
    stem = shipped_runs.STEMS["shelf"]
    keys = SHELF_CASE | shipped_runs.VARIANTS[variant](stem)
    answer = cp.solve(cp.load(ROOT / "problems" / f"{stem}.toml", keys))
    return {sex: answer.capable.share(sex) for sex in ("male", "female")}
