"""Writing a figure to its file."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt


def save_figure(fig: plt.Figure, path: Path, *, tight: bool = True) -> Path:
    """Write ``fig`` to ``path`` (its folder made if needed) and close it; ``tight`` lays
    it out first."""
    if tight:
        fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
