"""docs/low_back.md: the compression at L5/S1 of the shipped problems, at their start
postures (``torques``) and over their runs as shipped (``simulate``), as the package
computes them (``low-back``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp

from . import parallel, runs, wall
from .regions import Region
from .session import ROOT, Session

#: The wall files, whose runs as shipped the wall generator makes anyway: their stem → line.
WALL = {stem: line for line, stem in wall.LINES.items()}
#: The other shipped problems the page simulates.
OTHERS = ("standing_shelf_box", "standing_overhead_drill", "seated_assembly")


def minus(value: float) -> str:
    """A whole number with a typographic minus: -49.2 → '−49'."""
    return f"{value:.0f}".replace("-", "−")


def run_summary(stem: str) -> dict[str, Any]:
    """The summary of the shipped problem ``stem`` simulated as it is."""
    return cp.simulate(cp.load(ROOT / "problems" / f"{stem}.toml")).summary()


def prefetch() -> None:
    """Start the runs in the background."""
    parallel.submit(run_summary, [(stem,) for stem in OTHERS])
    wall.prefetch()


def summary(stem: str) -> dict[str, Any]:
    """The run's summary, the wall's from the wall generator's runs."""
    if stem in WALL:
        return wall.facts(WALL[stem], "whole")
    return parallel.compute(run_summary, [(stem,)])[stem,]


def facts(stem: str) -> dict[str, Any]:
    """What the page says of one run: ``outcome`` ('exhausted at 41 s', 'held to the end,
    1800 s'), the ``low_back`` summary's numbers, ``peak_shear`` as text and
    ``design_pct``, the peak compression as a share of the design limit [%]."""
    s = summary(stem)
    back, lost = s["low_back"], s["task"]["lost"]
    if lost is None:
        outcome = f"held to the end, {s['duration_s']:.0f} s"
    else:
        verb = "exhausted" if "exhausted" in lost["reason"] else "lost"
        outcome = f"{verb} at {lost['time_s']:.0f} s"
    return back | {
        "outcome": outcome,
        "peak_shear": minus(back["peak_shear_N"]),
        "design_pct": 100 * back["peak_compression_N"] / back["limits_N"]["design"],
    }


def values(region: Region, session: Session) -> dict[str, Any]:
    """``start[STEM]``: the low back (:class:`LowBack`, N) of each problem of ``start=``
    at its start posture; ``run[STEM]``: :func:`facts` of each problem of ``runs=``;
    ``answer``: the low back of ``problem=`` (with ``set=``) at ``posture='DOF=deg;...'``."""
    found: dict[str, Any] = {
        "start": {
            stem: cp.torques(cp.load(session.folder / "problems" / f"{stem}.toml")).low_back
            for stem in filter(None, region.args.get("start", "").split(","))
        },
        "run": {stem: facts(stem) for stem in filter(None, region.args.get("runs", "").split(","))},
    }
    if "problem" in region.args:
        posture = runs.overrides(region.args.get("posture", ""))
        found["answer"] = cp.torques(runs.problem(region, session), posture).low_back
    return found
