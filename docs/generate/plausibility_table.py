"""docs/plausibility.md: the report's thresholds (``plausibility-data``, from
``plausibility.toml``) and what it flags on the shipped problems' runs
(``plausibility-runs``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp
from casadi_posture.data import parameters

from . import comfort_runs, shipped_runs
from .regions import Region
from .session import ROOT, Session

#: The problems whose runs as shipped the page sums up together.
QUIET = ("wall", "m25", "m45", "drill")
#: The seated worker's lumbar flexion weight the page tries (``tasks[1].joint_weights``).
SEATED_WEIGHT = 10.0


def prefetch() -> None:
    """Start the page's runs in the background."""
    shipped_runs.prefetch(
        [("shelf", "shipped"), ("shelf", "whole_body"), ("seated", "shipped")]
        + [(n, "shipped") for n in QUIET]
    )


def thresholds(region: Region, session: Session) -> dict[str, Any]:
    """``p[NAME]``: every threshold of plausibility.toml by its name without the file's
    prefix (``{p[trunk_twist]:.0f}``), ``pct[NAME]`` a fraction of the range in % and
    ``cm[NAME]`` a length in cm."""
    table = {
        k.removeprefix("plausibility."): v.value for k, v in parameters.load("plausibility").items()
    }
    hundredths = {k: 100 * v for k, v in table.items()}
    return {"p": table, "pct": hundredths, "cm": hundredths}


def posture(summary: dict[str, Any], label: str) -> dict[str, Any]:
    """The plausibility report of the run's posture ``label`` ('start', 'end')."""
    return next(p for p in summary["plausibility"]["postures"] if p["label"] == label)


def flags(summary: dict[str, Any]) -> str:
    """The kinds of the run's plausibility flags (:func:`comfort_runs.kinds`), or 'none'."""
    return comfort_runs.kinds(summary["plausibility"]["flags"])


def verdict(extension_deg: float) -> str:
    """'under the 10° flagged' or 'beyond the 10° flagged' (``trunk_extension``)."""
    limit = parameters.load("plausibility")["plausibility.trunk_extension"].value
    return f"{'beyond' if extension_deg > limit else 'under'} the {limit:g}° flagged"


def values(region: Region, session: Session) -> dict[str, Any]:
    """``shelf``: the asymmetry at the ``start`` and ``end`` [deg] and ``flags`` as shipped;
    ``shelf_whole``: the whole-body run's ``flags``, ``turn_deg`` and ``bend_deg`` (the
    largest lumbar rotation and bending over the run [deg]); ``seated``: the lumbar
    extension at the start [deg] (``extension_deg``, and its :func:`verdict`), with the
    lumbar flexion's weight at :data:`SEATED_WEIGHT` (``weighted_deg``, ``weight``), and
    the run's ``flags``; ``quiet``: the runs of :data:`QUIET` as shipped, ``flags`` (the kinds
    of all their flags, or 'none') and ``idle_deg`` (the idle limbs' farthest from neutral
    over them [deg])."""
    shelf = shipped_runs.summary("shelf", "shipped")
    whole = shipped_runs.summary("shelf", "whole_body")
    rotation, bending = (whole["extremes"][d] for d in ("lumbar_rotation", "lumbar_bending"))
    seated = shipped_runs.problem("seated", "shipped")
    weighted = cp.load(
        ROOT / "problems" / f"{shipped_runs.STEMS['seated']}.toml",
        {"tasks[1].joint_weights.lumbar_flexion": SEATED_WEIGHT},
    )
    quiet = [shipped_runs.summary(n, "shipped") for n in QUIET]
    extension = -cp.solve(seated).posture_deg["lumbar_flexion"]
    return {
        "shelf": {
            "start": posture(shelf, "start")["asymmetry_deg"],
            "end": posture(shelf, "end")["asymmetry_deg"],
            "flags": flags(shelf),
        },
        "shelf_whole": {
            "flags": flags(whole),
            "turn_deg": max(abs(rotation["min"]), abs(rotation["max"])),
            "bend_deg": max(abs(bending["min"]), abs(bending["max"])),
        },
        "seated": {
            "extension_deg": extension,
            "verdict": verdict(extension),
            "weighted_deg": -cp.solve(weighted).posture_deg["lumbar_flexion"],
            "weight": SEATED_WEIGHT,
            "flags": flags(shipped_runs.summary("seated", "shipped")),
        },
        "quiet": {
            "flags": comfort_runs.kinds([f for s in quiet for f in s["plausibility"]["flags"]]),
            "idle_deg": max(
                limb["from_neutral_deg"]
                for s in quiet
                for p in s["plausibility"]["postures"]
                for limb in p["idle_limbs"]
            ),
        },
    }
