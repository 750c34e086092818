"""Figures of work–rest schedules: fatigue over time with the rest periods shaded, and the
sustainable duty cycle against the rest time."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from casadi_posture.output.key_postures import title
from casadi_posture.output.saving import save_figure
from casadi_posture.output.time_axis import time_unit
from casadi_posture.simulation import SimulationResult

#: Colour of the shaded rest periods.
REST_COLOUR = "#cfe3f5"

#: Groups drawn in a schedule figure: the most tired ones.
DRAWN_GROUPS = 6

#: Work cycles a run's figure draws step by step; a run of more is drawn beside them as
#: each cycle's peak and trough.
DETAIL_CYCLES = 4

#: A run longer than this [s] has its cycles' peaks and troughs drawn against hours.
HOURS_FROM_S = 2 * 3600.0


def rest_spans(result: SimulationResult) -> list[tuple[float, float]]:
    """The rest periods as (start, end) times [s]: a rest step k at k·dt stands for the
    interval ((k−1)·dt, k·dt], so a run of rest steps a..b rests from (a−1)·dt to b·dt."""
    tl = result.timeline
    resting = np.array([p == "rest" for p in tl.phase], dtype=bool)
    edges = np.flatnonzero(np.diff(np.concatenate([[False], resting, [False]]).astype(int)))
    dt = result.problem.spec.simulation.time_step_s
    return [(tl.time[a] - dt, tl.time[b - 1]) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def cycle_envelope(result: SimulationResult) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each work cycle's start [s], and the peak and trough of every group's fatigue over
    it (cycles × groups). Cycle c is steps c·P+1 … (c+1)·P of a P-step cycle (its hold,
    then its rest; step 0, the start, is in cycle 0). A last cycle the run's end cut short
    is left out (its hold, cut, would read as a drop of fatigue), unless the run stopped
    in it (at the threshold: its peak is where it stopped) or it is the only one; a run
    without a schedule is one cycle."""
    tl, dt = result.timeline, result.problem.spec.simulation.time_step_s
    if tl.time.size == 0:
        return np.zeros(0), tl.fatigue, tl.fatigue
    schedule = result.schedule
    period = schedule.period_steps if schedule is not None else max(tl.time.size - 1, 1)
    cycle = np.maximum(np.arange(tl.time.size) - 1, 0) // period
    if result.stop == "completed" and (tl.time.size - 1) % period and cycle[-1] > 0:
        cycle = cycle[cycle < cycle[-1]]
    starts = np.flatnonzero(np.diff(cycle, prepend=-1))
    fatigue = tl.fatigue[: cycle.size]
    return (
        cycle[starts] * period * dt,
        np.maximum.reduceat(fatigue, starts, axis=0),
        np.minimum.reduceat(fatigue, starts, axis=0),
    )


def _drawn(result: SimulationResult) -> list[tuple[int, str]]:
    """The most tired groups (at most ``DRAWN_GROUPS`` that tire at all) in the body's
    order, each with its colour."""
    fatigue = result.timeline.fatigue
    peak = fatigue.max(axis=0) if fatigue.size else np.zeros(len(result.problem.body.half_joints))
    tired = [k for k in np.argsort(-peak, kind="stable")[:DRAWN_GROUPS] if peak[k] > 0]
    return [(int(k), f"C{i}") for i, k in enumerate(sorted(tired))]


def _thresholds(ax: Axes, result: SimulationResult) -> None:
    """Both thresholds as horizontal lines, the fatigue axis from 0 to just above 1."""
    s = result.settings
    ax.axhline(s.fatigue_threshold, color="tab:red", ls="--", lw=1, label="fatigue threshold")
    ax.axhline(s.recovery_threshold, color="tab:green", ls="--", lw=1, label="recovery threshold")
    ax.set_ylim(0, 1.05)
    ax.grid(alpha=0.3)


def _fatigue_panel(ax: Axes, result: SimulationResult, heading: str, frames: int = -1) -> str:
    """The most tired groups' fatigue over time (``time_unit``'s unit, which it returns)
    over the first ``frames`` frames (-1: all), both thresholds, rest periods shaded."""
    tl, halves = result.timeline, result.problem.body.half_joints
    time = tl.time if frames < 0 else tl.time[:frames]
    scale, unit = time_unit(time)
    end = time[-1] if time.size else 0.0
    spans = [(a, min(b, end)) for a, b in rest_spans(result) if a < end]
    for start, stop in spans:
        ax.axvspan(start / scale, stop / scale, color=REST_COLOUR, lw=0, zorder=0)
    drawn = _drawn(result)
    for k, colour in drawn:
        ax.plot(
            time / scale, tl.fatigue[: time.size, k], lw=1.5, color=colour, label=halves[k].name
        )
    if not drawn:
        ax.set_xlim(0.0, max(end / scale, 1e-9))
        ax.text(0.5, 0.3, "no group tires: fatigue stays at 0", transform=ax.transAxes, ha="center")
    _thresholds(ax, result)
    if spans:
        ax.fill_between([], [], color=REST_COLOUR, label="rest (load put down)")
    ax.set_ylabel("fatigue level")
    ax.set_title(heading, fontsize=9, loc="left")
    return unit


def _envelope_panel(ax: Axes, result: SimulationResult, heading: str) -> str:
    """Each work cycle's peak (line) and trough (the band's floor) of the most tired
    groups' fatigue, at the cycle's start (hours for a run over ``HOURS_FROM_S``, else
    ``time_unit``'s unit, which it returns), and both thresholds: a shift of hundreds of
    cycles read as the trend of its cycles, not as a band of overlapping curves."""
    halves = result.problem.body.half_joints
    start, peak, trough = cycle_envelope(result)
    span = float(result.timeline.time[-1]) if result.timeline.time.size else 0.0
    scale, unit = (3600.0, "h") if span > HOURS_FROM_S else time_unit(np.array([0.0, span]))
    x = start / scale
    for k, colour in _drawn(result):
        name = halves[k].name
        ax.fill_between(x, trough[:, k], peak[:, k], color=colour, alpha=0.15, lw=0)
        ax.plot(x, peak[:, k], color=colour, lw=1.5, gid=f"peak {name}")
        ax.plot(x, trough[:, k], color=colour, lw=0.6, gid=f"trough {name}")
    _thresholds(ax, result)
    ax.set_title(heading, fontsize=9, loc="left")
    return unit


def _whole(result: SimulationResult, drawn: int) -> str:
    """``all 6 cycles``, or ``the 244 whole cycles of 245`` when the run's end cut the last
    one short (``cycle_envelope`` leaves it out)."""
    tl, schedule = result.timeline, result.schedule
    begun = -(-(tl.time.size - 1) // schedule.period_steps) if schedule is not None else 1
    return f"all {drawn} cycles" if drawn == begun else f"the {drawn} whole cycles of {begun} begun"


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
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return save_figure(fig, path)


def plot_runs(runs: Sequence[tuple[str, SimulationResult]], path: Path) -> Path:
    """``runs_figure`` of ``runs`` written to ``path``."""
    return save_figure(runs_figure(runs), path, tight=False)


def runs_figure(runs: Sequence[tuple[str, SimulationResult]]) -> Figure:
    """One row per labelled run (e.g. the two ends of a duty-cycle bracket), the label its
    heading: its first ``DETAIL_CYCLES`` work cycles in detail, rests shaded, and beside
    them, for a run of more cycles, every cycle's peak and trough over the whole run. Each
    panel has its own time axis: a run that stops at the threshold after minutes stays
    readable beside one of a whole shift."""
    fig = Figure(figsize=(11.0, 0.4 + 3.0 * len(runs)), dpi=120, layout="constrained")
    rows = fig.subfigures(len(runs), 1, squeeze=False)[:, 0]
    for row, (label, result) in zip(rows, runs, strict=True):
        row.suptitle(label, x=0.01, ha="left", fontsize=10, fontweight="bold")
        start = cycle_envelope(result)[0]
        both = start.size > DETAIL_CYCLES
        axes = row.subplots(1, 2 if both else 1, squeeze=False)[0]
        if both:
            frames = int(np.searchsorted(result.timeline.time, start[DETAIL_CYCLES], "right"))
            shown = f"the first {DETAIL_CYCLES} cycles"
        else:
            frames, shown = -1, "the whole run"
        unit = _fatigue_panel(axes[0], result, f"{shown}: {_schedule_text(result)}", frames)
        axes[0].set_xlabel(f"time ({unit})")
        handles, labels = axes[0].get_legend_handles_labels()
        if both:
            heading = f"{_whole(result, start.size)}: each one's peak and trough of fatigue"
            unit = _envelope_panel(axes[1], result, heading)
            axes[1].set_xlabel(f"time at the cycle's start ({unit})")
            handles.append(Patch(color="0.6", alpha=0.4))
            labels.append("a cycle's peak (line)\nto trough (band)")
        row.legend(handles, labels, fontsize=7, loc="outside right center")
    return fig


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
