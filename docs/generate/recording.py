"""The shipped recording evaluated once per check, in the background, for the prose of
every page that quotes it (``recording``), with what docs/motion.md says of its fit, of
OpenSim's answer, of a shift of lifts and of her hold (:mod:`.motion_fit`) and, in a
process of its own, the other IK solver's reading."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp

from . import motion_fit, parallel
from .regions import Region
from .session import ROOT, Session

#: The problem file and the recording it drives, in the repository.
CASE = ("problems/recorded_box_transfer.toml", "problems/recordings/box_transfer.c3d")


def evaluate(problem: str, motion: str) -> dict[str, Any]:
    """The recording evaluated on the problem: its summary, ``groups``, each half-joint's
    summary entry by name with ``peak_time_s``, the first time of its peak load [s], and
    :func:`.motion_fit.findings`; ``q``, its joint angles [rad]."""
    loaded = cp.load(ROOT / problem)
    recording = cp.read_motion(loaded, ROOT / motion)
    run = cp.evaluate(loaded, recording)
    summary, frame = run.summary(), run.to_frame().set_index("time_s")
    groups = {
        h["half_joint"]: h | {"peak_time_s": frame[f"load_{h['half_joint']}_pct_mvc"].idxmax()}
        for h in summary["half_joints"]
    }
    found = motion_fit.findings(loaded, recording, motion, summary)
    return summary | {"groups": groups, "q": recording.q} | found


def prefetch() -> None:
    """Start the evaluation, and the other solver's reading, in the background."""
    parallel.submit(evaluate, [CASE])
    parallel.submit(motion_fit.other_angles, [CASE])


def values(region: Region, session: Session) -> dict[str, Any]:
    """:func:`evaluate` of the shipped recording, and ``solvers_apart_deg``: the power of
    ten within which the other IK solver reads the same angles [deg] ("1e-5")."""
    found = parallel.compute(evaluate, [CASE])[CASE]
    other = parallel.compute(motion_fit.other_angles, [CASE])[CASE]
    return found | {"solvers_apart_deg": motion_fit.solvers_apart(found["q"], other)}
