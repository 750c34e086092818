"""Static answers at one posture: each half-joint's load and endurance, by the rule the
simulation follows (feasibility, and one rule for "unlimited").

- A group that carries nothing (the antagonist of the one holding the load) never tires.
- A load above 100 %MVC exceeds the group's strength: the posture cannot be held at all,
  so the endurance is 0 and the group is "over strength".
- Otherwise the endurance is the fatigue model's time from rest to exhaustion at that
  constant load, ``inf`` where the model accumulates no fatigue (below ``T_0`` for
  ``threshold``, below the sustainable load for ``3cc_r``): the time the simulation of
  the same constant load would take to reach a fatigue level of 1.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from casadi_posture.biomech.torques import Torques
from casadi_posture.problem import Problem

#: A load above this exceeds the group's maximum voluntary torque [%MVC].
STRENGTH_PCT_MVC = 100.0

Verdict = Literal["carries nothing", "unlimited", "limited", "over strength"]


@dataclass(frozen=True)
class GroupLoad:
    """One half-joint at one posture: strength and torque [N·m], load [%MVC], endurance [s]
    (``inf`` unlimited, 0 over strength) and the verdict that explains the endurance."""

    name: str
    dof: str
    strength: float
    torque: float
    load_pct_mvc: float
    endurance_s: float
    verdict: Verdict

    @property
    def endurance_min(self) -> float:
        return self.endurance_s / 60.0

    @property
    def over_strength(self) -> bool:
        return self.verdict == "over strength"


def endurance(problem: Problem, group: int, load_pct_mvc: float) -> tuple[float, Verdict]:
    """Endurance [s] of half-joint ``group`` under a constant load [%MVC], and its verdict."""
    if load_pct_mvc == 0.0:
        return math.inf, "carries nothing"
    if load_pct_mvc > STRENGTH_PCT_MVC:
        return 0.0, "over strength"
    region = problem.body.half_joints[group].region
    seconds = float(problem.fatigue.endurance_time_s(load_pct_mvc, region))
    return seconds, "unlimited" if math.isinf(seconds) else "limited"


def group_loads(problem: Problem, torques: Torques) -> list[GroupLoad]:
    """Every half-joint's load and endurance at the posture of ``torques``."""
    out = []
    loads = torques.load_pct_mvc
    for k, half in enumerate(problem.body.half_joints):
        load = float(loads[k])
        seconds, verdict = endurance(problem, k, load)
        out.append(
            GroupLoad(
                half.name,
                half.dof,
                float(torques.strength[k]),
                float(torques.half_joint_torque[k]),
                load,
                seconds,
                verdict,
            )
        )
    return out


def limiting(groups: Sequence[GroupLoad]) -> GroupLoad | None:
    """The group with the shortest endurance (the highest load on a tie); None when no group
    ever tires."""
    finite = [g for g in groups if math.isfinite(g.endurance_s)]
    if not finite:
        return None
    return min(finite, key=lambda g: (g.endurance_s, -g.load_pct_mvc))


def law(problem: Problem) -> str:
    """The recovery law and its parameters, in one line."""
    settings = problem.fatigue.settings()
    parts = [str(settings["recovery_law"])]
    if "load_threshold_pct_mvc" in settings:
        parts.append(f"T_0 = {settings['load_threshold_pct_mvc']:g} %MVC")
    rates = ", ".join(f"{k} {v:g}" for k, v in settings["recovery_rate_per_s"].items())
    parts.append(f"R = {rates} 1/s (×{settings['rest_multiplier']:g} when unloaded)")
    if "fatigue_rate_per_s" in settings:
        fatigue = ", ".join(f"{k} {v:g}" for k, v in settings["fatigue_rate_per_s"].items())
        parts.append(f"F = {fatigue} 1/s")
    return "; ".join(parts)


def rule(problem: Problem) -> str:
    """The rule behind every endurance of this problem, in one line."""
    return f"{problem.fatigue.rule()}; 0 above {STRENGTH_PCT_MVC:g} %MVC (over strength)"
