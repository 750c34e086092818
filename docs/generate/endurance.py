"""docs/endurance.md: every endurance model against Frey-Law & Avin's meta-analysis, as the
package's models compute it (``endurance-table``), and the recovery laws' constants for
the prose (``endurance``)."""

from __future__ import annotations

from typing import Any

from casadi_posture.biomech.endurance import endurance_model
from casadi_posture.biomech.fatigue import ThreeCompartmentFatigue

from .regions import Region
from .session import Session

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


def values(region: Region, session: Session) -> dict[str, Any]:
    """``recovery_rate[REGION]`` [1/s] of ``3cc_r`` (Frey-Law 2012), ``sustainable_pct_mvc
    [REGION]``: the load 100·R/(R + F) [%MVC] it holds for ever, and ``minutes[MODEL]
    [REGION][LOAD]``: the static endurance [min] of ``frey_law_avin`` and ``manenica`` in the
    ``regions=`` at the whole ``loads=`` (comma-separated, %MVC)."""
    known = {p.name: p.value for p in ThreeCompartmentFatigue(REGIONS).parameters()}
    rate = {
        (place, kind): known[f"fatigue.frey_law_2012.{place}.{kind}_rate"]
        for place in REGIONS
        for kind in ("fatigue", "recovery")
    }
    loads = [int(x) for x in region.args.get("loads", "").split(",") if x]
    places = [x for x in region.args.get("regions", "").split(",") if x]
    return {
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
