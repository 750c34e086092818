"""Potvin's (2012) guideline of the maximum acceptable effort (MAE) of a repetitive task
against its duty cycle (DC), for a whole shift:

    MAE = 1 − (DC − 1/T)^p          (fractions of MVC and of the cycle; T = 28 800 s)

One second of effort in an 8-hour shift is acceptable at 100 % MVC; a continuous effort
(DC = 1) at almost none. It was fitted to the efforts workers chose as acceptable in
psychophysical studies of upper-limb tasks, so it answers "would people accept this for a
shift?", where our duty cycle answers "does the model's fatigue stay below its threshold
over the horizon?". Parameters and sources: ``data/acceptable_effort.toml``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from casadi_posture.data import parameters

PERCENT = 100.0


@dataclass(frozen=True)
class Guideline:
    """The MAE equation's exponent ``p``, its shift ``T`` [s], its root-mean-square
    difference from the studies [%MVC] and the joint regions its data cover."""

    exponent: float
    shift_s: float
    rms_difference_pct_mvc: float
    regions: tuple[str, ...]

    @classmethod
    def from_data(cls) -> Guideline:
        """The shipped guideline (``acceptable_effort.*``)."""
        table = parameters.load("acceptable_effort")
        return cls(
            table["acceptable_effort.exponent"].value,
            table["acceptable_effort.shift_s"].value,
            table["acceptable_effort.rms_difference_pct_mvc"].value,
            tuple(table["acceptable_effort.regions"].value),
        )

    def mae_pct_mvc(self, duty_cycle_pct: float) -> float:
        """The maximum acceptable effort [%MVC] at a duty cycle [%] (100 at or below one
        second per shift)."""
        fraction = min(max(duty_cycle_pct / PERCENT, 0.0), 1.0) - 1.0 / self.shift_s
        return PERCENT * (1.0 - max(fraction, 0.0) ** self.exponent)

    def duty_cycle_pct(self, effort_pct_mvc: float) -> float:
        """The largest duty cycle [%] at which an effort [%MVC] is acceptable (the equation
        solved for DC): 100 at 0 %MVC, one second per shift at 100 %MVC or more."""
        if not math.isfinite(effort_pct_mvc):
            raise ValueError(f"effort {effort_pct_mvc!r} %MVC is not a number")
        effort = min(max(effort_pct_mvc / PERCENT, 0.0), 1.0)
        return PERCENT * min(1.0, (1.0 - effort) ** (1.0 / self.exponent) + 1.0 / self.shift_s)

    def covers(self, region: str) -> bool:
        """Whether the guideline's data include tasks of this joint region."""
        return region in self.regions
