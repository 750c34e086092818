"""Figures, drawn with matplotlib's Agg backend into files."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from .curve import TorqueCurve


def plot_torque_curve(curve: TorqueCurve, path: Path, title: str) -> Path:
    """The paper's Fig. 3: passive, external, active and minus-active torque over the range."""
    deg = np.degrees(curve.angles)
    fig, ax = plt.subplots(figsize=(7.0, 4.5), dpi=120)
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.plot(deg, curve.passive, color="tab:blue", lw=2, label="passive τp")
    ax.plot(deg, curve.external, color="black", lw=1.5, label="external τe")
    ax.plot(deg, curve.active, color="tab:red", lw=2, label="active τa = -(τp + τe)")
    ax.plot(deg, -curve.active, color="tab:red", lw=1.2, ls="--", label="-τa")
    for zero in curve.zeros:
        ax.axvline(np.degrees(zero.angle), color="tab:green", lw=0.8, ls=":")
        ax.plot(np.degrees(zero.angle), 0.0, "o", color="tab:green")
    span = max(np.max(np.abs(curve.external)), 1.0) * 2.5
    ax.set_ylim(-span, span)
    ax.set_xlim(deg[0], deg[-1])
    ax.set_xlabel(f"{curve.dof} (deg)")
    ax.set_ylabel("torque (N·m)")
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
