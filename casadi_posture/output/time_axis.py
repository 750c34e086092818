"""The time axis of a run's figures: minutes for a run longer than 5 minutes, seconds for
a shorter one (a recorded work cycle of a few seconds)."""

from __future__ import annotations

import numpy as np

#: A run longer than this [s] has its figures' time in minutes.
MINUTES_FROM_S = 300.0


def time_unit(time_s: np.ndarray) -> tuple[float, str]:
    """The divisor from seconds and the unit's name (``min`` or ``s``) for a run whose
    frames are at ``time_s`` [s]."""
    span = float(time_s[-1] - time_s[0]) if len(time_s) else 0.0
    return (60.0, "min") if span > MINUTES_FROM_S else (1.0, "s")


def in_unit(time_s: np.ndarray) -> tuple[np.ndarray, str]:
    """``time_s`` [s] in the run's unit (``time_unit``), and that unit's name."""
    scale, unit = time_unit(time_s)
    return np.asarray(time_s, dtype=float) / scale, unit
