"""Figures of work–rest schedules: the duty-cycle figure's per-cycle peaks and troughs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.lines import Line2D

from casadi_posture.output.schedule_plots import DETAIL_CYCLES, runs_figure
from casadi_posture.problem import load_problem
from casadi_posture.simulation import SimulationResult, simulate

HORIZONTAL = Path(__file__).resolve().parents[1] / "problems" / "holding_horizontal.toml"


def _run(t_on: float, t_off: float, duration: float, **kwargs: bool) -> SimulationResult:
    keys = {"schedule.t_on_s": t_on, "schedule.t_off_s": t_off}
    return simulate(load_problem(HORIZONTAL, {**keys, "simulation.duration_s": duration}), **kwargs)


def _by_hand(result: SimulationResult, cycle_steps: int) -> list[list[float]]:
    """The frames of each work cycle, split where a hold follows a rest (the start joins
    the first cycle), in plain Python; a last cycle shorter than ``cycle_steps`` dropped
    when the run went to its end."""
    cycles: list[list[int]] = [[0]]
    for k in range(1, len(result.timeline.phase)):
        if result.timeline.phase[k] == "hold" and result.timeline.phase[k - 1] == "rest":
            cycles.append([])
        cycles[-1].append(k)
    if result.stop == "completed" and len(cycles[-1]) < cycle_steps:
        cycles.pop()
    return cycles


def _line(ax: Axes, gid: str) -> Line2D:
    return next(line for line in ax.get_lines() if line.get_gid() == gid)


@pytest.mark.parametrize(
    ("t_on", "t_off", "duration", "stop", "whole"),
    [(40.0, 20.0, 500.0, "completed", 8), (60.0, 10.0, 1200.0, "fatigue_threshold", 5)],
)
def test_the_envelope_is_each_cycles_peak_and_trough(
    t_on: float, t_off: float, duration: float, stop: str, whole: int
) -> None:
    """The right-hand panel draws, per group, the highest and lowest fatigue of each work
    cycle at the cycle's start: the 8 whole cycles of a 500 s run of 60 s cycles (the 9th,
    cut by the run's end, left out), and all 5 of a run stopped at the threshold in its
    5th (its peak the threshold); the left panel draws the first cycles step by step."""
    result = _run(t_on, t_off, duration, stop_at_threshold=stop != "completed")
    assert result.stop == stop
    fig = runs_figure([("the run", result)])
    detail, envelope = fig.subfigs[0].axes
    cycles = _by_hand(result, int(t_on + t_off))
    assert len(cycles) == whole
    fatigue, halves = result.timeline.fatigue, result.problem.body.half_joints
    drawn = [line.get_gid().split(" ", 1)[1] for line in envelope.get_lines() if line.get_gid()]
    assert "shoulder_flexors" in drawn and "elbow_flexors" in drawn
    for name in set(drawn):
        k = next(i for i, h in enumerate(halves) if h.name == name)
        peak, trough = _line(envelope, f"peak {name}"), _line(envelope, f"trough {name}")
        assert list(peak.get_ydata()) == [max(fatigue[c, k]) for c in cycles]
        assert list(trough.get_ydata()) == [min(fatigue[c, k]) for c in cycles]
        assert np.allclose(np.asarray(peak.get_xdata()) * 60.0, np.arange(whole) * (t_on + t_off))
    if stop == "fatigue_threshold":
        assert max(_line(envelope, f"peak {n}").get_ydata()[-1] for n in drawn) >= 0.8
    shown = max(line.get_xdata()[-1] for line in detail.get_lines() if len(line.get_xdata()))
    seconds = {"time (s)": 1.0, "time (min)": 60.0}[detail.get_xlabel()]
    assert shown * seconds == pytest.approx(DETAIL_CYCLES * (t_on + t_off))
    assert envelope.get_xlabel() == "time at the cycle's start (min)"
