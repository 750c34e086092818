"""The answer of a design (``Design``, its gain and ``to_dict``) and the sweep of the
objective over one free quantity's bounds, an independent check of the optimum."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from casadi_posture import static
from casadi_posture.biomech.low_back import MODEL
from casadi_posture.biomech.low_back import limits as compression_limits
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.workplace_design.objectives import (
    CHECK_RELATIVE,
    CHECK_SHARE_PCT,
    COMPRESSION_UNIT,
    Score,
    score,
    score_gain,
)
from casadi_posture.workplace_design.quantities import Free, as_overrides

#: A design value within this of a bound [m] is reported at that bound.
BOUND_TOLERANCE_M = 1e-6


@dataclass(frozen=True)
class Design:
    """A design and its checks.

    ``free`` the design variables; ``best_m`` their values at the optimum [m]; ``start``,
    ``best`` and ``check`` the objective at the start (IK), at the NLP's answer and by the
    IK re-solved at the best design (a compression by ``LowBackModel.evaluate``);
    ``kept``/``dropped`` the priority levels kept as equalities or dropped;
    ``status``/``success``/``iterations``/``wall_time_s`` IPOPT's; ``notes`` say what to
    know, ``flags`` why the answer cannot be used as it is.
    """

    problem: Problem
    objective: str
    free: tuple[Free, ...]
    best_m: tuple[float, ...]
    start: Score
    best: Score
    check: Score
    start_answer: static.StaticAnswer
    best_answer: static.StaticAnswer
    check_answer: static.StaticAnswer
    kept: tuple[str, ...]
    dropped: tuple[str, ...]
    status: str
    success: bool
    iterations: int
    wall_time_s: float
    kept_residual: float
    posture_gap_deg: float
    agrees: bool
    notes: tuple[str, ...]
    flags: tuple[str, ...]

    @property
    def unit(self) -> str:
        """The JSON key of the objective's value, with its unit."""
        units = {"endurance": "endurance_min", "compression": COMPRESSION_UNIT}
        return units.get(self.objective, "capable_pct")

    @property
    def gain_unit(self) -> str:
        """The unit of ``gain``."""
        units = {"endurance": "min", "compression": "N"}
        return units.get(self.objective, "percentage points")

    @property
    def gain(self) -> float:
        """The answer: the IK re-solved at the best design − start [min or percentage
        points] (``inf``: the re-solve is unlimited), or start − re-solved for the
        compression [N] (its reduction). What a person at the design would do, as far as the
        IK predicts it; ``nlp_gain`` is the NLP's own."""
        return score_gain(self.start, self.check, self.objective)

    @property
    def nlp_gain(self) -> float:
        """The gain of the NLP's posture at the best design over the start (as ``gain``)."""
        return score_gain(self.start, self.best, self.objective)

    @property
    def ratio(self) -> float | None:
        """re-solved / start [-] (``inf``: from a finite to an unlimited endurance; below 1:
        a compression reduced; None from a start of 0, where no ratio exists)."""
        if math.isinf(self.check.value) and math.isinf(self.start.value):
            return 1.0
        return self.check.value / self.start.value if self.start.value > 0 else None

    def at_bound(self, j: int) -> str | None:
        """'lower' or 'upper' when design variable j ends at that bound, else None."""
        f, v = self.free[j], self.best_m[j]
        if v <= f.lower_m + BOUND_TOLERANCE_M:
            return "lower"
        if v >= f.upper_m - BOUND_TOLERANCE_M:
            return "upper"
        return None

    def overrides(self) -> dict[str, float]:
        """The best design as problem-file overrides {key: value [m]}."""
        return as_overrides(self.free, self.best_m)

    def to_dict(self) -> dict[str, Any]:
        """Everything the command prints, as plain data (units in the key names; an
        endurance of None is unlimited); ``notes`` the problem's (spec/slips.py), then the
        design's."""
        unit = self.unit
        return {
            "problem": str(self.problem.path),
            "objective": self.objective,
            "free": [
                {
                    "keys": list(f.keys),
                    "lower_m": f.lower_m,
                    "upper_m": f.upper_m,
                    "start_m": f.start_m,
                    "best_m": self.best_m[j],
                    "at_bound": self.at_bound(j),
                }
                for j, f in enumerate(self.free)
            ],
            "levels_kept": list(self.kept),
            "levels_dropped": list(self.dropped),
            "start": self.start.to_dict(unit),
            "best": self.best.to_dict(unit),
            "gain": {
                "absolute": self.gain,
                "unit": self.gain_unit,
                "direction": "reduction: start − re-solved"
                if self.objective == "compression"
                else "increase: re-solved − start",
                "ratio": self.ratio,
                "of": "the IK re-solved at the best design",
                "nlp_absolute": self.nlp_gain,
                "note": "the re-solve is unlimited (null: no finite gain)"
                if math.isinf(self.gain)
                else None,
            },
            "ipopt": {
                "status": self.status,
                "success": self.success,
                "iterations": self.iterations,
                "wall_time_s": self.wall_time_s,
            },
            "kept_levels_residual": self.kept_residual,
            "check": {
                **self.check.to_dict(unit),
                "agrees": self.agrees,
                "tolerance": (
                    f"{CHECK_SHARE_PCT:g} percentage points"
                    if self.objective.startswith("capable-")
                    else f"{100 * CHECK_RELATIVE:g} % of the NLP's {self.objective}"
                ),
                "posture_gap_deg": self.posture_gap_deg,
                "solver": self.check_answer.ik.solver if self.check_answer.ik else None,
            },
            **self._low_back(),
            "notes": [*self.problem.notes, *self.notes],
            "flags": list(self.flags),
        }

    def _low_back(self) -> dict[str, Any]:
        """The compression objective's model and NIOSH limits [N] (nothing for the others)."""
        if self.objective != "compression":
            return {}
        return {"low_back": {"model": MODEL, "niosh_limits_N": compression_limits()}}


@dataclass(frozen=True)
class SweepPoint:
    """The objective by the re-solved IK at one value [m] of a design variable, and whether
    that IK achieved every level the design kept (if not, the task is not held there and
    the objective means nothing)."""

    value_m: float
    score: Score
    kept: bool


def sweep(design: Design, values: Sequence[float]) -> list[SweepPoint]:
    """The objective by the re-solved IK (the file's solver) at each value [m] of the one
    design variable, the rest as in the file: an independent check of the optimum."""
    problem, quantity = design.problem, design.free[0]
    kept = [int(name.split(":")[0]) for name in design.kept]
    out = []
    for value in values:
        at = problem_from_data(problem.data, problem.path, dict.fromkeys(quantity.keys, value))
        answer = static.solve(at)
        held = all(answer.levels[k - 1].achieved for k in kept)
        out.append(SweepPoint(float(value), score(answer, design.objective), held))
    return out
