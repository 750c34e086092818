"""Figures of a design (``casadi-posture design --out``): the objective by the re-solved IK
over one free quantity's bounds, or, when several quantities are free, the loads of the
groups (or the L5/S1 compression) at the start and the best design."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from casadi_posture.biomech.low_back import limits as compression_limits
from casadi_posture.output.axes import axis_label, with_unit
from casadi_posture.output.saving import save_figure
from casadi_posture.workplace_design.answer import Design, SweepPoint

#: Points of the one-key sweep over its bounds.
SWEEP_POINTS = 15

#: Groups shown in the multi-key bar chart (the most loaded at the start or the best).
SHOWN_GROUPS = 12


def _label(design: Design) -> str:
    if design.objective == "endurance":
        return "endurance of the limiting group (min)"
    if design.objective == "compression":
        return "L5/S1 compression (N), lower is better"
    return f"share of {design.objective.removeprefix('capable-')}s capable (%)"


def _niosh(ax: Axes, highest: float) -> float:
    """The NIOSH design limit [N] as a dashed line, and the upper limit when the ``highest``
    compression shown [N] is above the design limit; returns the top that shows them [N]."""
    limit = compression_limits()
    ax.axhline(limit["design"], color="tab:orange", lw=1.0, ls="--", label="NIOSH design limit")
    if highest <= limit["design"]:
        return limit["design"] * 1.1
    ax.axhline(limit["upper"], color="tab:red", lw=1.0, ls="--", label="NIOSH upper limit")
    return limit["upper"] * 1.1


def plot_sweep(design: Design, points: Sequence[SweepPoint], path: Path) -> Path:
    """The objective by the re-solved IK against the one free quantity [m], with the start
    and the NLP's best (its own value and the re-solved check) marked; an unlimited endurance
    is drawn as a triangle on the top edge, a value where the IK does not keep the task
    (out of reach) as a grey cross."""
    free = design.free[0]
    x = np.array([p.value_m for p in points])
    y = np.array([p.score.value for p in points])
    kept = np.array([p.kept for p in points])
    finite = np.isfinite(y)
    marks = [design.start.value, design.best.value, design.check.value]
    highest = max([*y[finite], *(v for v in marks if math.isfinite(v)), 1e-9])
    top = highest * 1.15
    fig = Figure(figsize=(7.0, 4.5), dpi=120)
    ax = fig.subplots()
    good = kept & finite
    ax.plot(x[good], y[good], "o-", color="tab:blue", lw=1.5, ms=4, label="IK re-solved")
    if (kept & ~finite).any():
        unlimited = x[kept & ~finite]
        ax.plot(
            unlimited,
            np.full(unlimited.size, top),
            "^",
            color="tab:blue",
            ms=8,
            label="IK re-solved: unlimited",
        )
    if (~kept).any():
        ax.plot(
            x[~kept],
            np.where(finite, y, top)[~kept],
            "x",
            color="0.5",
            ms=8,
            label="IK misses a kept level (task not held)",
        )
    for value, at, style, label in (
        (design.start.value, free.start_m, ("s", "black"), "start (IK)"),
        (design.best.value, design.best_m[0], ("*", "tab:red"), "best (NLP)"),
        (design.check.value, design.best_m[0], ("D", "tab:orange"), "best, IK re-solved"),
    ):
        shown = value if math.isfinite(value) else top
        ax.plot(
            at,
            shown,
            style[0],
            color=style[1],
            ms=11 if style[0] == "*" else 8,
            mfc="none" if style[0] == "D" else style[1],
            mew=1.5,
            label=label,
            zorder=3,
        )
    ax.axvline(design.best_m[0], color="tab:red", lw=0.8, ls=":")
    if design.objective == "compression":
        top = max(top, _niosh(ax, highest))
    ax.set_ylim(0.0, top * 1.05)
    pad = 0.02 * (free.upper_m - free.lower_m)
    ax.set_xlim(free.lower_m - pad, free.upper_m + pad)
    ax.set_xlabel(with_unit(*axis_label(design.problem.data, free.name)))
    ax.set_ylabel(_label(design))
    ax.set_title(f"{design.problem.path.name}: design for {design.objective}", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return save_figure(fig, path)


def plot_loads(design: Design, path: Path) -> Path:
    """The load [%MVC] of the most loaded groups at the start (IK) and the best design
    (NLP posture), with the load threshold T_0 when the law has one."""
    names = [h.name for h in design.problem.body.half_joints]
    start = design.start_answer.torques.load_pct_mvc
    best = design.best_answer.torques.load_pct_mvc
    order = np.argsort(-np.maximum(start, best))[:SHOWN_GROUPS]
    order = [k for k in order if max(start[k], best[k]) > 0] or list(order[:1])
    position = np.arange(len(order))
    fig = Figure(figsize=(8.0, 4.5), dpi=120)
    ax = fig.subplots()
    ax.bar(position - 0.2, start[order], 0.4, color="0.55", label="start (IK)")
    ax.bar(position + 0.2, best[order], 0.4, color="tab:red", label="best (NLP)")
    threshold = design.problem.fatigue.settings().get("load_threshold_pct_mvc")
    if threshold is not None:
        ax.axhline(float(threshold), color="black", lw=0.8, ls="--", label="T_0")
    ax.set_xticks(position, [names[k] for k in order], rotation=40, ha="right", fontsize=8)
    ax.set_ylabel("load (%MVC)")
    ax.set_title(
        f"{design.problem.path.name}: group loads, design for {design.objective}", fontsize=10
    )
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def plot_compression(design: Design, path: Path) -> Path:
    """The L5/S1 compression [N] at the start (IK), at the best design (NLP posture) and by
    the IK re-solved there, with the NIOSH limits."""
    names = ["start (IK)", "best (NLP)", "best, IK re-solved"]
    values = [design.start.value, design.best.value, design.check.value]
    fig = Figure(figsize=(6.0, 4.5), dpi=120)
    ax = fig.subplots()
    bars = ax.bar(names, values, 0.5, color=["0.55", "tab:red", "tab:orange"])
    ax.bar_label(bars, fmt="%.0f N", fontsize=8)
    top = max(max(values) * 1.15, _niosh(ax, max(values)))
    ax.set_ylim(0.0, top * 1.05)
    ax.set_ylabel(_label(design))
    ax.set_title(f"{design.problem.path.name}: design for compression", fontsize=10)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)
