"""low_back.png: a run's compression and shear at L5/S1 over time, with the NIOSH limits
drawn and named (docs/low_back.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from casadi_posture.biomech.low_back import MODEL, limits
from casadi_posture.output.key_postures import recoveries, title
from casadi_posture.output.low_back import StepLoads
from casadi_posture.output.saving import save_figure
from casadi_posture.output.time_axis import in_unit
from casadi_posture.simulation import SimulationResult

#: The compression zones' colours: below the design limit, between the limits, above both.
ZONE_COLOURS = ("#2ca02c", "#ff7f0e", "#d62728")
#: Head room above the highest line drawn, as a fraction of it.
HEADROOM = 0.1


def plot_low_back(result: SimulationResult, steps: StepLoads, path: Path) -> Path:
    """The compression (top) with both NIOSH limits drawn, named and the zones between them
    shaded, and the forward shear (bottom), against time [min]; each recovery marked; a
    rest (nothing held, not computed) leaves a gap."""
    times, unit = in_unit(result.timeline.time)
    limit = limits()
    fig = Figure(figsize=(9.5, 6.5), dpi=120)
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(2, 1))
    high = (1 + HEADROOM) * max(limit["upper"], float(np.nanmax(steps.compression)))
    edges = (0.0, limit["design"], limit["upper"], high)
    for low, up, colour in zip(edges[:-1], edges[1:], ZONE_COLOURS, strict=True):
        top.axhspan(low, up, color=colour, alpha=0.1, lw=0, zorder=0)
    named = (
        (
            limit["design"],
            f"NIOSH design limit {limit['design']:g} N (above it: redesign the task)",
        ),
        (
            limit["upper"],
            f"NIOSH upper limit {limit['upper']:g} N (above it: hazardous to nearly all workers)",
        ),
    )
    for value, name in named:
        top.axhline(value, color="0.2", lw=1.2, ls="--")
        top.text(0.01, value, name, transform=top.get_yaxis_transform(), fontsize=8, va="bottom")
    top.step(times, steps.compression, where="post", lw=1.8, color="tab:blue")
    top.set_ylim(0.0, high)
    top.set_ylabel("compression at L5/S1 (N)")
    bottom.step(times, steps.shear, where="post", lw=1.5, color="tab:purple")
    bottom.axhline(0.0, color="0.5", lw=0.8)
    bottom.set_ylabel("shear at L5/S1 (N)\nforward +")
    span = float(np.nanmax(np.abs(steps.shear)))
    bottom.set_ylim(-(1 + HEADROOM) * span - 1.0, (1 + HEADROOM) * span + 1.0)
    for ax in (top, bottom):
        for k, step in enumerate(recoveries(result)):
            mark = "recovered (fatigue 0.5)" if k == 0 else None
            ax.axvline(times[step], color="tab:green", lw=1, ls=":", label=mark)
        ax.grid(alpha=0.25)
    if recoveries(result):
        top.legend(fontsize=7, loc="upper right")
    top.set_title(f"{title(result)}\n{MODEL}", fontsize=9)
    bottom.set_xlabel(f"time ({unit})")
    bottom.set_xlim(times[0], max(times[-1], times[0] + 1e-9))
    return save_figure(fig, path)
