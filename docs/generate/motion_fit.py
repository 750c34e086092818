"""What docs/motion.md and the README say of the shipped recording beyond its evaluation
(added to the ``recording`` generator's values, read from the same IK): the fit's
residuals, OpenSim's answer beside ours, the lift repeated over a shift, our model's
posture for her hold, and the other IK solver's reading."""

from __future__ import annotations

import math
import tomllib
from typing import Any, NamedTuple

import casadi as ca
import numpy as np

import casadi_posture as cp
from casadi_posture.api import scaled
from casadi_posture.ik.solvers import SOLVER_NAMES
from casadi_posture.motion.markers import read_c3d
from casadi_posture.motion.recording import between, repeat
from casadi_posture.problem import problem_from_data
from casadi_posture.runs.prediction import compare_prediction

from .session import ROOT

#: The lift played back to back as a work cycle until this time [s] (``--until``).
SHIFT_S = 400.0
#: pyomeca's OpenSim inverse kinematics of the trial, and its columns for our DOFs.
OPENSIM = "problems/recordings/box_transfer_opensim_ik.mot"
OPENSIM_DOFS = {
    "elbow": ("elbow_flexion_r", "elbow_flexion"),
    "wrist_flexion": ("wrist_flexion_r", "hand_r_Flex"),
    "pronation": ("forearm_pronation_r", "pro_sup"),
    "wrist_deviation": ("wrist_deviation_r", "hand_r_Add"),
}
#: The rows of the fit's table: the residual points whose names start with these.
FIT_ROWS = {
    "pelvis": ("pelvis",),
    "thorax": ("upper_trunk",),
    "joint_centres": ("elbow_r", "wrist_r", "knuckles_r"),
    "arm_markers": ("forearm_r", "hand_r"),
    "shoulder": ("shoulder_r",),
}
#: Her hold at the shelf [s] (``--between``), and the tasks docs/motion.md adds for it,
#: the hand's target her grip's mean position there [m].
HOLD_S = (3.2, 3.8)
HOLD_TASKS = """\
[[tasks]]
name = "hand_at_the_box"
kind = "position"
effector = "grip_r"
priority = 1
target_m = [{0:.2f}, {1:.2f}, {2:.2f}]

[[tasks]]
name = "comfort"
kind = "comfort"
priority = 2"""


class Span(NamedTuple):
    """The least and the greatest of some values; formatted as ``low–high`` with the
    format spec of each, or as one number when both read the same."""

    low: float
    high: float

    def __format__(self, spec: str) -> str:
        low, high = format(self.low, spec), format(self.high, spec)
        return low if low == high else f"{low}–{high}"


class Angle(float):
    """A signed value written as the pages write it: a minus sign (−), not a hyphen."""

    def __format__(self, spec: str) -> str:
        return super().__format__(spec).replace("-", "\N{MINUS SIGN}")


def ordinal(n: int) -> str:
    """1st, 2nd, 3rd, 4th, ..., 11th, ..., 23rd."""
    suffix = "th" if n % 100 in (11, 12, 13) else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def fit_table(residuals: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
    """Per row of :data:`FIT_ROWS`: the ``median_mm``, ``p95_mm`` (95th percentile) of its
    points' residuals, as a :class:`Span` over the points, ``largest_mm`` and
    ``largest_cm``, the largest of all. A point in no row raises (the table would miss it)."""
    rows: dict[str, list[np.ndarray]] = {row: [] for row in FIT_ROWS}
    for point, values in residuals.items():
        row = next((r for r, ps in FIT_ROWS.items() if point.split(".")[0] in ps), None)
        if row is None:
            raise ValueError(f"residual point {point!r} is in no row of the fit's table")
        rows[row].append(1000.0 * values)
    return {
        row: {
            "median_mm": Span(*_ends([np.median(v) for v in found])),
            "p95_mm": Span(*_ends([np.percentile(v, 95) for v in found])),
            "largest_mm": max(v.max() for v in found),
            "largest_cm": max(v.max() for v in found) / 10.0,
        }
        for row, found in rows.items()
    }


def _ends(values: list[float]) -> tuple[float, float]:
    return min(values), max(values)


def opensim(problem: cp.Problem, recording: cp.Recording) -> dict[str, Any]:
    """Our angles beside OpenSim's over its frames: ``span_s``, its first and last time
    [s]; per entry of :data:`OPENSIM_DOFS` the RMS difference [deg] (ours interpolated at
    its times) as ``<name>_rms_deg``; ``elbow_range_deg``, OpenSim's elbow flexion [deg]."""
    lines = (ROOT / OPENSIM).read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("endheader")) + 1
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[header + 1 :]])
    theirs = dict(zip(lines[header].split(","), rows.T, strict=True))
    time, names = theirs["time"], problem.body.dof_names
    found: dict[str, Any] = {"span_s": Span(time[0], time[-1])}
    for name, (ours, column) in OPENSIM_DOFS.items():
        angle = np.interp(time, recording.time, np.degrees(recording.q[:, names.index(ours)]))
        found[f"{name}_rms_deg"] = float(np.sqrt(np.mean((angle - theirs[column]) ** 2)))
    found["elbow_range_deg"] = Span(*_ends(list(theirs["elbow_flexion"])))
    return found


def shift(problem: cp.Problem, recording: cp.Recording) -> dict[str, Any]:
    """The lift back to back until :data:`SHIFT_S`: ``until_s``, ``cycle_s`` (a lift's
    period [s]), by half-joint the first time at the fatigue threshold ``threshold_s`` and
    the lift it falls in (``threshold_lift``, "16th"), and the first exhausted group's
    ``exhausted_s`` and ``exhausted_lift`` by its name."""
    repeated = repeat(recording, until_s=SHIFT_S)
    summary = cp.evaluate(problem, repeated).summary()
    cycle = float(repeated.time[recording.frames] - repeated.time[0])
    times = {h["half_joint"]: h["first_fatigue_threshold_s"] for h in summary["half_joints"]}
    times = {name: t for name, t in times.items() if t is not None}
    exhausted = summary["exhausted_group"]
    gone = {exhausted["half_joint"]: exhausted["time_s"]} if exhausted else {}
    return {
        "until_s": SHIFT_S,
        "cycle_s": cycle,
        "threshold_s": times,
        "threshold_lift": {n: ordinal(math.floor(t / cycle) + 1) for n, t in times.items()},
        "exhausted_s": gone,
        "exhausted_lift": {n: ordinal(math.floor(t / cycle) + 1) for n, t in gone.items()},
    }


def hold(problem: cp.Problem, recording: cp.Recording) -> dict[str, Any]:
    """Her hold at :data:`HOLD_S` (``window_s``) beside our model's posture for it:
    ``toml``, a fenced block of the tasks docs/motion.md adds (the target her grip's mean
    position there [m]), ``spread_cm``, how far her grip strays from that mean, and of
    ``evaluate --compare-prediction`` ``recorded`` and ``predicted``, each DOF's mean
    [deg], ``endurance_min``, the limiting group's endurance at the start [min] of each,
    and ``endurance_ratio``, the predicted one over the recorded one."""
    body = scaled(problem, recording.segment_lengths_m).body
    grip = ca.Function("grip", [body.q], [body.landmark("grip_r")])
    held = between(recording, *HOLD_S)
    xyz = np.asarray(grip.map(held.frames)(held.q.T)).T
    mean = xyz.mean(axis=0)
    tasks = HOLD_TASKS.format(*mean)
    with_tasks = problem_from_data(problem.data | tomllib.loads(tasks), problem.path)
    replayed = cp.evaluate(with_tasks, held).result
    compared = compare_prediction(replayed.problem, replayed)
    postures = compared.postures()
    endurance = next(o for o in compared.outcomes() if o["outcome"].startswith("its endurance"))
    return {
        "window_s": Span(*HOLD_S),
        "toml": f"```toml\n{tasks}\n```",
        "spread_cm": 100.0 * float(np.linalg.norm(xyz - mean, axis=1).max()),
        "recorded": {r["dof"]: Angle(r["recorded_mean_deg"]) for r in postures},
        "predicted": {r["dof"]: Angle(r["predicted_mean_deg"]) for r in postures},
        "endurance_min": {k: endurance[k] for k in ("recorded", "predicted")},
        "endurance_ratio": endurance["predicted"] / endurance["recorded"],
    }


def findings(
    problem: cp.Problem, recording: cp.Recording, motion: str, summary: dict[str, Any]
) -> dict[str, Any]:
    """Everything above of ``recording`` (read from the C3D file ``motion`` of the
    repository with ``problem``; ``summary`` its evaluation's), with ``file``: its
    ``markers``, ``rate_hz``, ``duration_s``, the problem's load ``mass_kg`` and ``held_s``
    window [s]; ``ik_solver``, the problem's; ``fit``, ``fit_arm_cm`` (the largest residual
    of the arm's points [cm]), ``fit_flagged_s`` (the first and last time a point is above
    the problem's limit [s]); and ``at_limit``, each DOF resting on a limit by name (its
    ``limit_deg``, ``seconds``)."""
    markers = read_c3d(ROOT / motion)
    spec = problem.spec.motion
    load = problem.loads[0]
    above = np.any([r > spec.max_marker_residual_m for r in recording.residuals.values()], axis=0)
    flagged, fit = recording.time[above], fit_table(recording.residuals)
    return {
        "file": {
            "markers": len(markers.labels),
            "rate_hz": 1.0 / float(np.median(np.diff(markers.time))),
            "duration_s": float(markers.time[-1] - markers.time[0]),
            "mass_kg": load.mass,
            "held_s": Span(*spec.held_s[load.name][0]),
        },
        "ik_solver": problem.spec.solver.name,
        "fit": fit,
        "fit_arm_cm": max(fit[row]["largest_cm"] for row in ("joint_centres", "arm_markers")),
        "fit_flagged_s": Span(flagged[0], flagged[-1]) if flagged.size else None,
        "at_limit": {
            h["dof"]: h | {"limit_deg": Angle(h["limit_deg"])}
            for h in summary["plausibility"]["held_at_limits"]
        },
        "opensim": opensim(problem, recording),
        "shift": shift(problem, recording),
        "hold": hold(problem, recording),
    }


def other_angles(problem: str, motion: str) -> np.ndarray:
    """The joint angles [rad] (frames × DOFs) that the IK solver the repository's
    ``problem`` file does not name reads from its C3D file ``motion``."""
    loaded = cp.load(ROOT / problem)
    other = next(name for name in SOLVER_NAMES if name != loaded.spec.solver.name)
    return cp.read_motion(loaded, ROOT / motion, solver=other).q


def solvers_apart(q: np.ndarray, other: np.ndarray) -> str:
    """The power of ten [deg] within which two readings' angles [rad] agree ("1e-5")."""
    apart = float(np.degrees(np.abs(q - other).max()))
    return f"1e{math.ceil(math.log10(apart))}" if apart > 0 else "0"
