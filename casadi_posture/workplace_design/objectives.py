"""The objectives and how an answer scores on each: the static endurance [min], the share
capable [%] of one sex, or the L5/S1 compression [N]; and how two scores compare (gain,
better, agree within the check tolerance)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from casadi_posture import static
from casadi_posture.biomech.capability import SEXES, Sex, capability
from casadi_posture.biomech.low_back import limits as compression_limits

OBJECTIVES = ("endurance", "capable-male", "capable-female", "compression")

#: The JSON key of a compression score [N].
COMPRESSION_UNIT = "compression_N"

#: The re-solved IK agrees with the NLP when its endurance or compression is within this
#: fraction of the NLP's [-], or its share capable within this many percentage points [%].
CHECK_RELATIVE = 0.01
CHECK_SHARE_PCT = 0.5


@dataclass(frozen=True)
class Score:
    """The objective at one design and posture: the static endurance [min] (``inf``:
    unlimited) or the share capable [%], with its limiting group, the group's region and
    load [%MVC]; or the L5/S1 compression [N] (no group: None)."""

    value: float
    group: str | None
    region: str | None
    load_pct_mvc: float | None

    def to_dict(self, unit: str) -> dict[str, Any]:
        if unit == COMPRESSION_UNIT:
            limit = compression_limits()
            return {
                unit: self.value,
                "above_niosh_design_limit": self.value > limit["design"],
                "above_niosh_upper_limit": self.value > limit["upper"],
            }
        return {
            unit: self.value,
            "limiting_group": self.group,
            "limiting_region": self.region,
            "limiting_load_pct_mvc": self.load_pct_mvc,
        }


def score(answer: static.StaticAnswer, objective: str) -> Score:
    """The objective of a static answer: the limiting group's endurance [min] (``inf`` when
    no group tires), the task's share capable [%] for the objective's sex, or the L5/S1
    compression [N] (``LowBackModel.evaluate`` at the answer's posture)."""
    problem, body = answer.problem, answer.problem.body
    if objective == "compression":
        assert answer.low_back is not None, "design() refuses a body without a lumbar joint"
        return Score(answer.low_back.compression, None, None, None)
    if objective == "endurance":
        group = answer.limiting
        if group is None:
            return Score(math.inf, None, None, None)
        k = [h.name for h in body.half_joints].index(group.name)
        return Score(
            group.endurance_min, group.name, body.half_joints[k].region, group.load_pct_mvc
        )
    sex = sex_of(objective)
    result = capability(
        static.population_strength(problem, answer.torques.strength),
        answer.torques.half_joint_torque,
    )
    weakest = result.weakest(sex)
    if weakest is None:
        return Score(result.share(sex), None, None, None)
    k = [h.name for h in body.half_joints].index(weakest.name)
    load = float(answer.torques.load_pct_mvc[k])
    return Score(result.share(sex), weakest.name, body.half_joints[k].region, load)


def sex_of(objective: str) -> Sex:
    sex = objective.removeprefix("capable-")
    assert sex in SEXES
    return sex  # type: ignore[return-value]


def score_gain(start: Score, end: Score, objective: str) -> float:
    """end − start [min or percentage points], start − end for the compression [N]; 0
    between two unlimited endurances."""
    if math.isinf(end.value) and math.isinf(start.value):
        return 0.0
    if objective == "compression":
        return start.value - end.value
    return end.value - start.value


def is_better(a: Score, b: Score, objective: str) -> bool:
    """Whether score ``a`` is better than ``b`` beyond the check tolerance (a lower
    compression is better)."""
    if objective == "endurance":
        return a.value > b.value * (1.0 + CHECK_RELATIVE)
    if objective == "compression":
        return a.value < b.value * (1.0 - CHECK_RELATIVE)
    return a.value > b.value + CHECK_SHARE_PCT


def scores_agree(a: Score, b: Score, objective: str) -> bool:
    """Whether two scores agree within the check tolerance (two unlimited ones do)."""
    if math.isinf(a.value) or math.isinf(b.value):
        return a.value == b.value
    if objective.startswith("capable-"):
        return abs(a.value - b.value) <= CHECK_SHARE_PCT
    return abs(a.value - b.value) <= CHECK_RELATIVE * max(abs(a.value), 1e-12)


def format_score(value: float, objective: str) -> str:
    """A score as the command prints it: N, % capable, or min (``unlimited``)."""
    if objective == "compression":
        return f"{value:.0f} N"
    if objective != "endurance":
        return f"{value:.2f} % capable"
    return "unlimited" if math.isinf(value) else f"{value:.3f} min"
