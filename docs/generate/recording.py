"""The shipped recording evaluated once per check, in the background, for the prose of
every page that quotes it (``recording``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp

from . import parallel
from .regions import Region
from .session import ROOT, Session

#: The problem file and the recording it drives, in the repository.
CASE = ("problems/recorded_box_transfer.toml", "problems/recordings/box_transfer.c3d")


def evaluate(problem: str, motion: str) -> dict[str, Any]:
    """The recording evaluated on the problem: its summary, and ``groups``, each
    half-joint's summary entry by name with ``peak_time_s``, the first time of its peak
    load [s]."""
    run = cp.evaluate(cp.load(ROOT / problem), ROOT / motion)
    summary, frame = run.summary(), run.to_frame().set_index("time_s")
    groups = {
        h["half_joint"]: h | {"peak_time_s": frame[f"load_{h['half_joint']}_pct_mvc"].idxmax()}
        for h in summary["half_joints"]
    }
    return summary | {"groups": groups}


def prefetch() -> None:
    """Start the evaluation in the background."""
    parallel.submit(evaluate, [CASE])


def values(region: Region, session: Session) -> dict[str, Any]:
    """:func:`evaluate` of the shipped recording."""
    return parallel.compute(evaluate, [CASE])[CASE]
