"""scores.png: a run's RULA and REBA per side over time, the action levels shaded and named
(docs/rula_reba.md)."""

from __future__ import annotations

from pathlib import Path
from textwrap import fill

import numpy as np
from matplotlib.figure import Figure

from casadi_posture.ergonomics import reba, rula
from casadi_posture.output.key_postures import recoveries, title
from casadi_posture.output.saving import save_figure
from casadi_posture.output.scores import SIDES, step_scores
from casadi_posture.output.time_axis import in_unit
from casadi_posture.simulation import SimulationResult

#: The bands' colours, from the lowest action level to the highest.
BAND_COLOURS = ("#2ca02c", "#bcbd22", "#ff7f0e", "#d62728", "#7f0000")
#: Characters per line of a band's name, written beside the axes.
NAME_WIDTH = 30
#: How far apart the sides' lines are drawn [score] where they coincide.
SIDE_OFFSET = 0.08


def bands(sheet: str) -> list[tuple[float, float, str]]:
    """Each action level's span of scores (low, high edge) and its name, lowest first."""
    uppers = rula.value(f"{sheet}.action_levels.upper_scores")
    out, low = [], 0.5
    for top in uppers:
        if sheet == "rula":
            level, action = rula.action_level(top)
            name = f"action level {level}: {action}"
        else:
            level, risk, action = reba.action_level(top)
            name = f"{risk} risk, action level {level}: action {action}"
        out.append((low, top + 0.5, name))
        low = top + 0.5
    return out


def plot_scores(result: SimulationResult, path: Path) -> Path:
    """RULA (top) and REBA (bottom) of each side over time [min], the action levels shaded
    and named, each recovery marked; a rest step (not scored) leaves a gap."""
    tl, steps = result.timeline, step_scores(result)
    times, unit = in_unit(tl.time)
    scored = next(s for s in steps if s)
    fig = Figure(figsize=(9.5, 6.5), dpi=120)
    axes = fig.subplots(2, 1, sharex=True)
    sheets = (
        ("rula", "RULA grand score", lambda s: s.rula.grand),
        ("reba", "REBA score", lambda s: s.reba.reba),
    )
    for ax, (sheet, axis_name, grade) in zip(axes, sheets, strict=True):
        for (low, high, name), colour in zip(bands(sheet), BAND_COLOURS, strict=False):
            ax.axhspan(low, high, color=colour, alpha=0.13, lw=0, zorder=0)
            ax.text(
                1.01,
                (low + high) / 2,
                fill(name, NAME_WIDTH),
                fontsize=7,
                color="0.25",
                transform=ax.get_yaxis_transform(),
                ha="left",
                va="center",
            )
        for i, side in enumerate(scored):
            shift = SIDE_OFFSET * (0.5 - i) if len(scored) > 1 else 0.0
            values = np.array([np.nan if s is None else grade(s[i]) for s in steps], dtype=float)
            ax.step(times, values + shift, where="post", lw=1.8, label=SIDES[side.side])
        for k, step in enumerate(recoveries(result)):
            mark = "recovered (fatigue 0.5)" if k == 0 else None
            ax.axvline(times[step], color="tab:green", lw=1, ls="--", label=mark)
        top = bands(sheet)[-1][1]
        ax.set_ylim(0.5, top)
        ax.set_yticks(range(1, int(top) + 1))
        ax.set_ylabel(axis_name)
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.25, axis="x")
    axes[0].set_title(title(result), fontsize=9)
    axes[-1].set_xlabel(f"time ({unit})")
    axes[-1].set_xlim(times[0], max(times[-1], times[0] + 1e-9))
    if len(scored) > 1:
        note = f"the sides' lines are drawn {SIDE_OFFSET:g} apart where they coincide"
        fig.text(0.01, 0.005, note, fontsize=6, color="0.4")
    return save_figure(fig, path)
