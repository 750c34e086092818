"""A recorded motion beside the one our model predicts for the same problem (``evaluate
--compare-prediction``; docs/motion.md): postures DOF by DOF, and what tired, when, and for
how long the task is held."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.output.plain import dumps
from casadi_posture.output.results import summary, time_mean, write_table
from casadi_posture.output.run_files import RUN_FILES
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.simulation import SimulationResult, simulate

#: DOFs the console names, most different first.
SHOWN_DOFS = 5


@dataclass(frozen=True)
class PredictionComparison:
    """A replayed recording (``recorded``) and the simulation of the problem's own tasks over
    the same time (``predicted``), with their summaries."""

    recorded: SimulationResult
    predicted: SimulationResult
    recorded_summary: dict[str, Any]
    predicted_summary: dict[str, Any]

    def postures(self) -> list[dict[str, Any]]:
        """Per DOF [deg]: the recorded first frame and the predicted start, the two means over
        time and the root mean square of their difference, the prediction interpolated at the
        recorded frames' times (from the recording's first frame); most different first."""
        rec, pred = self.recorded.timeline, self.predicted.timeline
        time = rec.time - rec.time[0]
        rows = []
        for i, dof in enumerate(self.recorded.problem.body.dof_names):
            recorded = np.degrees(rec.q[:, i])
            predicted = np.degrees(np.interp(time, pred.time, pred.q[:, i]))
            rows.append(
                {
                    "dof": dof,
                    "recorded_first_deg": float(recorded[0]),
                    "predicted_start_deg": float(predicted[0]),
                    "recorded_mean_deg": time_mean(recorded, time),
                    "predicted_mean_deg": time_mean(predicted, time),
                    "rms_difference_deg": math.sqrt(time_mean((recorded - predicted) ** 2, time)),
                }
            )
        return sorted(rows, key=lambda r: -r["rms_difference_deg"])

    def outcomes(self) -> list[dict[str, Any]]:
        """What each run found, side by side: limiting group and its endurance at the start,
        the first group at the fatigue threshold and when, the exhausted group and when, how
        long the task is held [s], the peak L5/S1 compression [N], the worst RULA and REBA."""
        pairs = [_outcome(s) for s in (self.recorded_summary, self.predicted_summary)]
        return [
            {"outcome": name, "recorded": recorded[name], "predicted": predicted[name]}
            for recorded, predicted in [pairs]
            for name in recorded
        ]


def _outcome(report: dict[str, Any]) -> dict[str, Any]:
    limiting, first = report["limiting_group_at_start"], report["first_to_fatigue"]
    exhausted, back = report["exhausted_group"], report["low_back"]
    worst = (report["rula_reba"] or {}).get("worst") or {}
    return {
        "limiting group at start": limiting and limiting["half_joint"],
        "its endurance at start (min)": limiting and limiting["endurance_min"],
        "first at the fatigue threshold": first and first["half_joint"],
        "first at the fatigue threshold at (s)": first and first["time_s"],
        "exhausted": exhausted and exhausted["half_joint"],
        "exhausted at (s)": exhausted and exhausted["time_s"],
        "task held (s)": report["task"]["held_s"],
        "peak L5/S1 compression (N)": back and back.get("peak_compression_N"),
        "worst RULA": worst.get("rula", {}).get("score"),
        "worst REBA": worst.get("reba", {}).get("score"),
    }


def compare_prediction(problem: Problem, recorded: SimulationResult) -> PredictionComparison:
    """The problem's own tasks simulated over the recording's time span (its time step, at
    least one step), beside the replayed recording ``recorded``."""
    if not problem.spec.tasks:
        expected = "at least one task to predict a posture from (--compare-prediction)"
        raise ProblemError(problem.path, "tasks", MISSING, expected)
    tl = recorded.timeline
    step = problem.spec.simulation.time_step_s
    span = max(float(tl.time[-1] - tl.time[0]), step)
    timed = {"simulation.duration_s": span, "simulation.time_step_s": step}
    predicted = simulate(problem_from_data(problem.data, problem.path, timed))
    return PredictionComparison(recorded, predicted, summary(recorded), summary(predicted))


#: The comparison's own files in an evaluation's folder; its predicted run is in PREDICTED.
PREDICTION_FILES, PREDICTED = ("prediction.csv", "prediction.json"), "predicted"


def clear_prediction(out: Path) -> None:
    """Delete an earlier comparison's files from ``out`` (an evaluation written over with
    ``--force``): prediction.csv and .json, and the predicted run's files, with their folder
    when nothing else is in it; a user's own files are kept."""
    for name in PREDICTION_FILES:
        (out / name).unlink(missing_ok=True)
    folder = out / PREDICTED
    if folder.is_dir():
        for name in RUN_FILES:
            (folder / name).unlink(missing_ok=True)
        if not any(folder.iterdir()):
            folder.rmdir()


def write_prediction(comparison: PredictionComparison, out: Path) -> list[Path]:
    """prediction.csv (the postures, DOF by DOF) and prediction.json (the outcomes side by side
    and the postures) into ``out``."""
    rows = comparison.postures()
    table, data = (out / name for name in PREDICTION_FILES)
    write_table({k: [r[k] for r in rows] for k in rows[0]}, table)
    data.write_text(dumps({"outcomes": comparison.outcomes(), "postures": rows}) + "\n")
    return [table, data]
