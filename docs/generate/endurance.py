"""docs/endurance.md: every endurance model against Frey-Law & Avin's meta-analysis, as the
package's models compute it (``endurance-table``), the recovery laws' constants for the
prose (``endurance``) and the horizontal hold under each law (``recovery-laws``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp
from casadi_posture.biomech.endurance import endurance_model
from casadi_posture.biomech.fatigue import ThreeCompartmentFatigue

from . import parallel
from .regions import Region
from .session import ROOT, Session

#: The table's rows: joint regions and loads [%MVC].
REGIONS = ("shoulder", "elbow")
LOADS = (20, 30, 50, 70, 90)
#: The models set against the meta-analysis, in the table's column order.
MODELS = ("manenica", "rohmert", "3cc_r")


def endurance_s(model: str, load: float, region: str) -> float:
    """The static endurance [s] of ``model`` (``3cc_r``: its failure point) at ``load``
    [%MVC] in ``region``."""
    if model == "3cc_r":
        return float(ThreeCompartmentFatigue([region]).endurance_time_s(load, region))
    return float(endurance_model(model).endurance_time_s(load, region))


def table(region: Region, session: Session) -> str:
    """The Markdown table: each model's endurance [s] and its difference from the
    meta-analysis [%], per region and load."""
    header = ["region", "load (%MVC)", "Frey-Law & Avin 2010 (s)"]
    for model in MODELS:
        header += [f"`{model}` (s)", "vs data"]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for place in REGIONS:
        for load in LOADS:
            data = endurance_s("frey_law_avin", load, place)
            cells = [place, str(load), f"{data:.0f}"]
            for model in MODELS:
                value = endurance_s(model, load, place)
                cells += [f"{value:.0f}", f"{100 * (value / data - 1):+.0f} %"]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def than(low: float, high: float | None = None) -> str:
    """A difference from the data [%] in words, '42 % less', or a range of them of one
    sign, '36 to 80 % more'."""
    high = low if high is None else high
    word = "more" if low > 0 else "less" if high < 0 else None
    if word is None:
        return f"{low:+.0f} to {high:+.0f} %"
    ends = sorted({f"{abs(low):.0f}", f"{abs(high):.0f}"}, key=float)
    return f"{' to '.join(ends)} % {word}"


def spread(loads: list[int], off: list[float], args: dict[str, str]) -> tuple[float, float]:
    """The least and largest of ``off`` [%] over the ``loads`` [%MVC] within
    ``between=LO,HI`` (all without it)."""
    low, high = (float(x) for x in args.get("between", "0,100").split(","))
    inside = [value for load, value in zip(loads, off, strict=True) if low <= load <= high]
    return min(inside), max(inside)


def values(region: Region, session: Session) -> dict[str, Any]:
    """``recovery_rate[REGION]`` [1/s] of ``3cc_r`` (Frey-Law 2012), ``sustainable_pct_mvc
    [REGION]``: the load 100·R/(R + F) [%MVC] it holds for ever, and ``minutes[MODEL]
    [REGION][LOAD]``: the static endurance [min] of ``frey_law_avin`` and ``manenica`` in the
    ``regions=`` at the whole ``loads=`` (comma-separated, %MVC); ``than_data[REGION]
    [LOAD]``: how ``manenica`` differs from ``frey_law_avin`` there, in words ('42 % less'),
    and ``spread[REGION]`` over those loads (within ``between=LO,HI``; '36 to 80 % more')."""
    known = {p.name: p.value for p in ThreeCompartmentFatigue(REGIONS).parameters()}
    rate = {
        (place, kind): known[f"fatigue.frey_law_2012.{place}.{kind}_rate"]
        for place in REGIONS
        for kind in ("fatigue", "recovery")
    }
    loads = [int(x) for x in region.args.get("loads", "").split(",") if x]
    places = [x for x in region.args.get("regions", "").split(",") if x]
    off = {
        place: [
            100 * (endurance_s("manenica", x, place) / endurance_s("frey_law_avin", x, place) - 1)
            for x in loads
        ]
        for place in places
    }
    return {
        "than_data": {
            place: dict(zip(loads, map(than, off[place]), strict=True)) for place in places
        },
        "spread": {place: than(*spread(loads, off[place], region.args)) for place in places},
        "recovery_rate": {place: rate[place, "recovery"] for place in REGIONS},
        "sustainable_pct_mvc": {
            place: 100
            * rate[place, "recovery"]
            / sum(rate[place, k] for k in ("fatigue", "recovery"))
            for place in REGIONS
        },
        "minutes": {
            name: {
                place: {load: endurance_s(name, load, place) / 60 for load in loads}
                for place in places
            }
            for name in ("frey_law_avin", "manenica")
        },
    }


#: The recovery laws' runs of the horizontal hold: (law, T_0 [%MVC], None for 3cc_r).
LAW_CASES = [(law, t0) for law in ("threshold", "continuous") for t0 in (10, 15, 25)] + [
    ("3cc_r", None)
]


def law_run(law: str, t0: int | None) -> dict[str, Any]:
    """The horizontal hold simulated under ``law`` (with T_0 = ``t0`` [%MVC]): the
    limiting group's ``endurance_min`` at the start, ``first_s`` (the first group at the
    fatigue threshold [s]), ``exhausted`` (its words, or 'none'), ``cycles``, ``held``
    ('369', or '≥ 1800' for a run held to its end) and ``loads``, each group's load at
    the start [%MVC] by name."""
    keys: dict[str, Any] = {"fatigue.recovery_law": law}
    if t0 is not None:
        keys["fatigue.load_threshold_pct_mvc"] = t0
    run = cp.simulate(cp.load(ROOT / "problems" / "holding_horizontal.toml", keys))
    s = run.summary()
    exhausted, task = s["exhausted_group"], s["task"]
    return {
        "endurance_min": s["limiting_group_at_start"]["endurance_min"],
        "first_s": s["first_to_fatigue"]["time_s"] if s["first_to_fatigue"] else None,
        "exhausted": exhausted["half_joint"].replace("_", " ") if exhausted else "none",
        "cycles": s["fatigue_recovery_cycles"],
        "held": f"{'≥ ' if task['held_s_is_lower_bound'] else ''}{task['held_s']:.0f}",
        "loads": {h["half_joint"]: h["initial_load_pct_mvc"] for h in s["half_joints"]},
    }


def prefetch_laws() -> None:
    """Start the recovery laws' runs in the background."""
    parallel.submit(law_run, LAW_CASES)


def laws(region: Region, session: Session) -> dict[str, Any]:
    """``run[LAW][T_0]`` (``run[3cc_r][0]``): :func:`law_run` of each case, and
    ``low[LAW]``: '10 or 15' when T_0 = 10 and 15 give the same run, else '15' (the row
    then shows T_0 = 15)."""
    found = parallel.compute(law_run, LAW_CASES)
    runs: dict[str, dict[int, dict[str, Any]]] = {}
    for (law, t0), facts in found.items():
        runs.setdefault(law, {})[t0 or 0] = facts
    low = {
        law: "10 or 15" if runs[law][10] == runs[law][15] else "15"
        for law in ("threshold", "continuous")
    }
    return {"run": runs, "low": low}
