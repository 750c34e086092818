"""Figures of work–rest schedules: fatigue over time with the rest periods shaded, and the
sustainable duty cycle against the rest time."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from casadi_posture.output.key_postures import title
from casadi_posture.output.saving import save_figure
from casadi_posture.output.time_axis import time_unit
from casadi_posture.simulation import SimulationResult

#: Colour of the shaded rest periods.
REST_COLOUR = "#cfe3f5"

#: Groups drawn in a schedule figure: the most tired ones.
DRAWN_GROUPS = 6


def rest_spans(result: SimulationResult) -> list[tuple[float, float]]:
    """The rest periods as (start, end) times [s]: a rest step k at k·dt stands for the
    interval ((k−1)·dt, k·dt], so a run of rest steps a..b rests from (a−1)·dt to b·dt."""
    tl = result.timeline
    resting = np.array([p == "rest" for p in tl.phase], dtype=bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[False], resting, [False]]).astype(int)))
    dt = result.problem.spec.simulation.time_step_s
    return [(tl.time[a] - dt, tl.time[b - 1]) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _fatigue_panel(ax: Axes, result: SimulationResult, heading: str) -> str:
    """The most tired groups' fatigue over time (``time_unit``'s unit, which it returns),
    both thresholds, rest periods shaded."""
    tl, s = result.timeline, result.settings
    halves = result.problem.body.half_joints
    scale, unit = time_unit(tl.time)
    times = tl.time / scale
    spans = rest_spans(result)
    for start, end in spans:
        ax.axvspan(start / scale, end / scale, color=REST_COLOUR, lw=0, zorder=0)
    peak = tl.fatigue.max(axis=0) if tl.time.size else np.zeros(len(halves))
    drawn = [k for k in np.argsort(-peak, kind="stable")[:DRAWN_GROUPS] if peak[k] > 0]
    for k in sorted(drawn):
        ax.plot(times, tl.fatigue[:, k], lw=1.5, label=halves[k].name)
    ax.axhline(s.fatigue_threshold, color="tab:red", ls="--", lw=1, label="fatigue threshold")
    ax.axhline(s.recovery_threshold, color="tab:green", ls="--", lw=1, label="recovery threshold")
    if spans:
        ax.fill_between([], [], color=REST_COLOUR, label="rest (load put down)")
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("fatigue level")
    ax.set_title(heading, fontsize=9, loc="left")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return unit


def _schedule_text(result: SimulationResult) -> str:
    """``hold 60 s, rest 30 s`` on the step grid, or ``continuous hold``."""
    schedule = result.schedule
    if schedule is None:
        return "continuous hold"
    dt = schedule.dt_s
    return f"hold {schedule.hold_steps * dt:g} s, rest {schedule.rest_steps * dt:g} s"


def plot_schedule(result: SimulationResult, path: Path) -> Path:
    """Fatigue of the most tired groups over the run, the rest periods shaded (schedule.png)."""
    fig = Figure(figsize=(9.0, 4.0), dpi=120)
    ax = fig.subplots()
    unit = _fatigue_panel(ax, result, f"{title(result)} — {_schedule_text(result)}")
    ax.set_xlabel(f"time ({unit})")
    return save_figure(fig, path)


def plot_runs(runs: Sequence[tuple[str, SimulationResult]], path: Path) -> Path:
    """One fatigue panel per labelled run (e.g. the two ends of a duty-cycle bracket), each
    on its own time axis (a run that stops at the threshold after minutes stays readable
    beside one of a whole shift), rest periods shaded."""
    fig = Figure(figsize=(9.0, 1.0 + 2.9 * len(runs)), dpi=120)
    axes = fig.subplots(len(runs), 1, squeeze=False)
    for ax, (label, result) in zip(axes[:, 0], runs, strict=True):
        unit = _fatigue_panel(ax, result, f"{label}: {_schedule_text(result)}")
        ax.set_xlabel(f"time ({unit})")
    return save_figure(fig, path)


def plot_duty_vs_rest(
    t_off_s: Sequence[float],
    sustainable_s: Sequence[float | None],
    failing_s: Sequence[float | None],
    horizon_s: float,
    heading: str,
    path: Path,
) -> Path:
    """The longest hold per cycle found sustainable [s] against the rest time [s], a bar up
    to the shortest hold found to reach the threshold; a hold sustainable to the horizon
    (continuous) drawn as an upward triangle at the horizon, no sustainable hold as a cross
    at 0."""
    fig = Figure(figsize=(6.5, 4.2), dpi=120)
    ax = fig.subplots()
    found = [(r, t) for r, t, f in zip(t_off_s, sustainable_s, failing_s, strict=True) if f and t]
    if found:
        ax.plot(*zip(*found, strict=True), color="tab:blue", lw=0.8, alpha=0.5)
    for rest, good, bad in zip(t_off_s, sustainable_s, failing_s, strict=True):
        if bad is None:
            ax.plot(rest, horizon_s, "^", color="tab:green", ms=9)
        elif good is None:
            ax.plot(rest, 0.0, "x", color="tab:red", ms=9, mew=2)
        else:
            ax.plot([rest, rest], [good, bad], color="tab:blue", lw=2)
            ax.plot(rest, good, "o", color="tab:blue", ms=6)
    ax.plot([], [], "o-", color="tab:blue", label="sustainable hold (bar: up to the failing one)")
    ax.plot([], [], "^", color="tab:green", label=f"held continuously for {horizon_s:g} s")
    ax.plot([], [], "x", color="tab:red", mew=2, label="no hold sustainable")
    ax.set_xlabel("rest per cycle t_off (s)")
    ax.set_ylabel("longest sustainable hold per cycle t_on (s)")
    ax.set_title(heading, fontsize=9)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return save_figure(fig, path)
