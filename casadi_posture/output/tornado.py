"""The tornado plot of a sensitivity analysis: what matters most for a task's endurance."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from casadi_posture.output.saving import save_figure

#: The change of every input the bars show, in % of its value.
STEP_PCT = 10.0


def plot_tornado(rows: list[dict[str, object]], title: str, path: Path, top: int = 15) -> Path:
    """The change of the task's endurance [%] when each of the ``top`` inputs with the largest
    elasticity changes by ±10 % of its value (to first order: ±10 %·elasticity), largest at
    the top; ``rows`` as ``Sensitivity.ranked`` gives them."""
    shown = [r for r in rows if r["endurance_elasticity"] is not None][:top][::-1]
    fig = Figure(figsize=(8.5, 0.38 * len(shown) + 1.8))
    ax = fig.subplots()
    up = np.array([STEP_PCT * float(r["endurance_elasticity"]) for r in shown])
    y = np.arange(len(shown))
    ax.barh(y, up, color="tab:blue", label=f"input +{STEP_PCT:g} %")
    ax.barh(y, -up, color="tab:orange", alpha=0.7, label=f"input −{STEP_PCT:g} %")
    ax.axvline(0.0, color="black", lw=0.8)
    ax.set_yticks(y, [f"{r['key']} = {r['value']:.4g} {r['unit']}" for r in shown], fontsize=8)
    ax.set_xlabel("change of the task's static endurance (%), to first order")
    ax.set_title(title, fontsize=10)
    ax.grid(axis="x", alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    return save_figure(fig, path)
