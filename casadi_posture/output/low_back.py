"""Low-back compression and shear at L5/S1 in the outputs (docs/low_back.md): the console
lines and JSON of a static answer, a run's values per step (timeline columns, from one
batched call of the compiled model), its summary.json section and flag, and the row fields
of a batch or what-if case."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from casadi_posture.biomech.low_back import MODEL, OUTPUTS, LowBack, limits, low_back_model
from casadi_posture.body.loads import LOAD_PARAMETERS
from casadi_posture.output.per_run import once_per_run
from casadi_posture.simulation import SimulationResult
from casadi_posture.static import compression_flags

#: What is said instead of a number for a body without a lumbar joint.
NOT_COMPUTED = "not computed (the body has no lumbar joint)"


def muscle(sagittal_moment: float) -> str:
    """The muscle the model loads: the erector spinae against a flexing moment [N·m], the
    rectus abdominis against an extending one."""
    return "erector spinae" if sagittal_moment >= 0 else "rectus abdominis"


def above(compression: float | None) -> str | None:
    """The highest NIOSH limit a compression [N] is above: ``upper``, ``design`` or None."""
    limit = limits()
    if compression is None or compression <= limit["design"]:
        return None
    return "upper" if compression > limit["upper"] else "design"


def static_report(back: LowBack | None) -> dict[str, Any]:
    """A static answer's ``low_back`` as ``--json`` gives it: compression, forward and
    lateral shear, the muscle and its force [N], the sagittal moment [N·m], the NIOSH
    limits [N], the limit it is above, and the model; numbers null and a note for a body
    without a lumbar joint."""
    numbers = {
        "compression_N": None if back is None else back.compression,
        "shear_N": None if back is None else back.shear,
        "lateral_shear_N": None if back is None else back.lateral_shear,
        "muscle": None if back is None else muscle(back.sagittal_moment),
        "muscle_force_N": None if back is None else back.muscle_force,
        "sagittal_moment_Nm": None if back is None else back.sagittal_moment,
        "above_limit": None if back is None else above(back.compression),
    }
    note = NOT_COMPUTED if back is None else None
    return {"model": MODEL, **numbers, "limits_N": limits(), "note": note}


def lines(back: LowBack | None) -> list[str]:
    """The console lines of a static answer: the compression and shears, the muscle force,
    the model, and where the compression stands against the NIOSH limits."""
    if back is None:
        return [f"low back: {NOT_COMPUTED}"]
    return [
        f"low back, by the {MODEL}:",
        f"  compression {newtons(back.compression)}, shear {newtons(back.shear)} forward and "
        f"{newtons(back.lateral_shear)} to the left, {muscle(back.sagittal_moment)} force "
        f"{newtons(back.muscle_force)}",
        f"  {_standing(back.compression)}",
    ]


def newtons(force: float) -> str:
    """A force to the newton, ``0 N`` rather than ``-0 N``."""
    return f"{round(force)} N"


def _standing(compression: float) -> str:
    """Where a compression [N] stands against the NIOSH limits, both named."""
    limit, level = limits(), above(compression)
    where = {
        None: "below the design limit",
        "design": "ABOVE the design limit (flagged)",
        "upper": "ABOVE the upper limit (flagged)",
    }[level]
    return (
        f"NIOSH limits: {limit['design']:g} N design limit, {limit['upper']:g} N upper limit: "
        f"{where}"
    )


@dataclass(frozen=True)
class StepLoads:
    """A run's compression and forward shear at L5/S1 per step [N]; NaN on a rest step (the
    load put down, the relaxed posture not modelled)."""

    compression: np.ndarray
    shear: np.ndarray


@once_per_run
def step_low_back(result: SimulationResult) -> StepLoads | None:
    """The compression and shear at every step of a run holding its loads (a recording: the
    loads each frame holds), from one batched call of the compiled model over the stacked
    postures; None for a body without a lumbar joint."""
    tl, problem = result.timeline, result.problem
    model = low_back_model(problem.body, problem.loads)
    steps = None
    if model is not None:
        n = tl.time.size
        values = np.full((2, n), np.nan)
        if n:
            loads = model.default_loads
            if tl.held is not None:  # a recording: each step with the loads it holds
                loads = (tl.held.repeat(LOAD_PARAMETERS, axis=1) * loads).T
            out = model.function.map(n)(tl.q.T, loads)
            for row, name in enumerate(("compression", "shear")):
                values[row] = np.asarray(out[OUTPUTS.index(name)], dtype=float).ravel()
            values[:, [phase == "rest" for phase in tl.phase]] = np.nan
        steps = StepLoads(values[0], values[1])
    return steps


def timeline_columns(steps: StepLoads | None) -> dict[str, list[float | None]]:
    """``compression_N`` and ``shear_N`` per step (empty on a rest step; none for a body
    without a lumbar joint)."""
    if steps is None:
        return {}
    return {
        "compression_N": [None if np.isnan(v) else v for v in steps.compression.tolist()],
        "shear_N": [None if np.isnan(v) else v for v in steps.shear.tolist()],
    }


def run_report(result: SimulationResult, steps: StepLoads | None) -> dict[str, Any]:
    """summary.json's ``low_back``: the model, the peak compression [N] and its first time
    [s], the shear of largest size (signed, forward +) and its time, the time above each
    NIOSH limit [s] (a step's value held until the next step, as the figures draw it), the
    limits; numbers null and a note when not computed or when no step was held."""
    limit = limits()
    report: dict[str, Any] = {
        "model": MODEL,
        "peak_compression_N": None,
        "peak_compression_time_s": None,
        "peak_shear_N": None,
        "peak_shear_time_s": None,
        "time_above_3400N_s": None,
        "time_above_6400N_s": None,
        "limits_N": limit,
        "note": NOT_COMPUTED if steps is None else None,
    }
    if steps is None:
        return report
    if np.all(np.isnan(steps.compression)):
        return report | {"note": "no held step"}
    time = result.timeline.time
    dt = np.diff(time, append=time[-1])
    peak = int(np.nanargmax(steps.compression))
    shear = int(np.nanargmax(np.abs(steps.shear)))
    return report | {
        "peak_compression_N": float(steps.compression[peak]),
        "peak_compression_time_s": float(time[peak]),
        "peak_shear_N": float(steps.shear[shear]),
        "peak_shear_time_s": float(time[shear]),
        "time_above_3400N_s": float(dt[steps.compression > limit["design"]].sum()),
        "time_above_6400N_s": float(dt[steps.compression > limit["upper"]].sum()),
    }


def run_flags(report: dict[str, Any]) -> list[str]:
    """The run's flag when its peak compression is above the design limit (summary.json's
    ``low_back``), with its time and the time above each limit."""
    peak = report["peak_compression_N"]
    if peak is None:
        return []
    detail = (
        f" (the peak, at {report['peak_compression_time_s']:g} s; above "
        f"{report['limits_N']['design']:g} N for {report['time_above_3400N_s']:g} s, above "
        f"{report['limits_N']['upper']:g} N for {report['time_above_6400N_s']:g} s)"
    )
    return compression_flags(peak, detail)


def run_lines(report: dict[str, Any]) -> list[str]:
    """A run's console lines from summary.json's ``low_back``: the peak compression and
    shear with their times and the time above each limit, or why there is none."""
    if report["peak_compression_N"] is None:
        return [f"  low back: {report['note']}"]
    limit = report["limits_N"]
    return [
        f"  low back at L5/S1: peak compression {newtons(report['peak_compression_N'])} at "
        f"{report['peak_compression_time_s']:g} s, peak shear {newtons(report['peak_shear_N'])} "
        f"at {report['peak_shear_time_s']:g} s; above the NIOSH design limit "
        f"({limit['design']:g} N) for {report['time_above_3400N_s']:g} s, above the upper "
        f"limit ({limit['upper']:g} N) for {report['time_above_6400N_s']:g} s ({MODEL})"
    ]


def run_row(report: dict[str, Any]) -> dict[str, float | None]:
    """A simulated case's row fields from summary.json's ``low_back``: the peak compression
    [N] and the time above the design limit [s] (None: not computed)."""
    return {key: report[key] for key in ("peak_compression_N", "time_above_3400N_s")}


def static_row(back: LowBack | None) -> dict[str, float | None]:
    """A static case's row fields: the compression [N] as its peak, no time above."""
    compression = None if back is None else back.compression
    return {"peak_compression_N": compression, "time_above_3400N_s": None}
