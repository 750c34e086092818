"""Share of a population able to exert the torques of a task ("% capable", as 3DSSPP reports).

For each half-joint g and sex s the maximum voluntary torque of people of the problem's
body size is taken as normal with mean μ_{g,s} and SD σ_{g,s} [N·m]. The share able to
exert the group's required torque τ_g [N·m] is

    P_{g,s} = Φ((μ_{g,s} − τ_g) / σ_{g,s}) × 100 %,   Φ(z) = (1 + erf(z / √2)) / 2,

and the task's share for a sex is that of its weakest group, min_g P_{g,s}. A group that
carries nothing (τ_g = 0) counts as 100 %.

Means: for the body's sex the problem's strength of the group at the posture considered
(the shipped default, possibly posture-dependent, or what the file sets); for the other
sex that times the ratio of the two sexes' shipped defaults at the problem's stature, mass
and age (``default_strength``). A group without a shipped default takes the same mean for
both sexes. SDs: σ = CV × μ, with CV the c1_sd / c1 of Anderson et al. 2007 pooled over its
young and middle-aged rows for hip, knee and ankle flexion/extension (a measured spread),
else the estimate ``strength.population_cv`` (``strength.toml``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import casadi as ca
import numpy as np

from casadi_posture.biomech.strength import anderson_young, default_strength, known_groups
from casadi_posture.data import parameters
from casadi_posture.data.parameters import data_name
from casadi_posture.spec.schema import BodySpec

Sex = Literal["male", "female"]
SEXES: tuple[Sex, Sex] = ("male", "female")
#: How each sex is named in text and figures.
PEOPLE: dict[Sex, str] = {"male": "men", "female": "women"}
SdStatus = Literal["measured", "estimate"]

#: A design convention, not a physiological limit: a task "most workers can do" when at least
#: these shares [%] of men and of women are capable. The NIOSH 1981 Work Practices Guide's
#: action limit was set at a load over 99 % of men and 75 % of women can lift, and 3DSSPP
#: users quote the same pair as a strength design limit.
DESIGN_LIMIT_PCT: dict[Sex, float] = {"male": 99.0, "female": 75.0}


@dataclass(frozen=True)
class PopulationStrength:
    """The strength of one half-joint among people of the problem's body size: mean and SD
    [N·m] per sex, where the means come from (``source``) and where the SDs come from
    (``sd_source``), ``sd_status`` "measured" (a study's SD) or "estimate" (our CV)."""

    name: str
    mean: dict[Sex, float]
    sd: dict[Sex, float]
    source: str
    sd_source: str
    sd_status: SdStatus


@dataclass(frozen=True)
class GroupCapability:
    """One half-joint's required torque [N·m] and the share of each sex able to exert it [%]."""

    population: PopulationStrength
    required: float
    capable_pct: dict[Sex, float]

    @property
    def name(self) -> str:
        return self.population.name


@dataclass(frozen=True)
class Capability:
    """The shares capable of every half-joint and of the task (its weakest group) per sex."""

    groups: tuple[GroupCapability, ...]

    def share(self, sex: Sex) -> float:
        """The task's share capable [%]: the minimum over groups (100 with no group)."""
        return min((g.capable_pct[sex] for g in self.groups), default=100.0)

    def weakest(self, sex: Sex) -> GroupCapability | None:
        """The group with the smallest share (the largest required torque on a tie); None when
        no group carries anything."""
        loaded = [g for g in self.groups if g.required > 0.0]
        return min(loaded, key=lambda g: (g.capable_pct[sex], -g.required), default=None)

    def below_design_limit(self, sex: Sex) -> bool:
        """Whether the task's share is below ``DESIGN_LIMIT_PCT`` for ``sex``."""
        return self.share(sex) < DESIGN_LIMIT_PCT[sex]

    def to_dict(self) -> dict[str, Any]:
        """The task's share [%] and weakest group per sex, and the design limits [%]."""
        out: dict[str, Any] = {}
        for sex in SEXES:
            weakest = self.weakest(sex)
            out[sex] = {
                "capable_pct": self.share(sex),
                "weakest_group": None if weakest is None else weakest.name,
                "design_limit_pct": DESIGN_LIMIT_PCT[sex],
                "below_design_limit": self.below_design_limit(sex),
            }
        return out

    def task_line(self) -> str:
        """The task's share per sex and its weakest group, in one line."""
        parts = []
        for sex, people in PEOPLE.items():
            weakest = self.weakest(sex)
            limit = "no group loaded" if weakest is None else f"weakest: {weakest.name}"
            parts.append(f"{self.share(sex):.1f} % of {people} ({limit})")
        return "capable of the task: " + ", ".join(parts)

    def sd_line(self) -> str:
        """Which population SDs are measured and which are our estimate, in one line."""
        names = [g.name for g in self.groups if g.population.sd_status == "measured"]
        measured = list(dict.fromkeys(data_name(n) for n in names))  # both sides as one
        estimated = len(self.groups) - len(names)
        cv = f"CV {population_cv().value:g} × mean, our estimate"
        if not measured:
            return f"population SDs: {cv}, for every group"
        others = f"; {cv}, for the other {estimated} groups" if estimated else ""
        return f"population SDs: Anderson 2007 (measured) for {', '.join(measured)}{others}"

    def notes(self) -> list[str]:
        """One line per sex whose share is below its design limit (a convention, not a flag:
        the answer stands, the task suits fewer people than designers usually aim at)."""
        out = []
        for sex, people in PEOPLE.items():
            if self.below_design_limit(sex):
                out.append(
                    f"{self.share(sex):.1f} % of {people} capable, below the "
                    f"{DESIGN_LIMIT_PCT[sex]:g} % design limit (a convention: NIOSH 1981 "
                    "action limit, 99 % of men and 75 % of women)"
                )
        return out


def normal_cdf(z: Any) -> Any:
    """Φ(z) = (1 + erf(z/√2))/2 of a float, a numpy array or a CasADi expression."""
    if isinstance(z, ca.SX | ca.MX | ca.DM):
        return 0.5 * (1.0 + ca.erf(z / math.sqrt(2.0)))
    if isinstance(z, np.ndarray):
        return 0.5 * (1.0 + np.vectorize(math.erf, otypes=[float])(z / math.sqrt(2.0)))
    return 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))


def share_capable(mean: Any, sd: Any, required: Any) -> Any:
    """Share [%] of a population whose strength ~ N(mean, sd²) [N·m] reaches ``required``
    [N·m]: Φ((mean − required)/sd) × 100; floats, numpy arrays or CasADi expressions.
    (The "carries nothing counts as 100 %" rule is ``capability``'s.)"""
    return 100.0 * normal_cdf((mean - required) / sd)


def population_cv() -> parameters.Parameter:
    """The coefficient of variation used where no population SD is known (an estimate)."""
    return parameters.load("strength")["strength.population_cv"]


def population(
    body: BodySpec,
    groups: Sequence[str],
    own: Mapping[str, str],
    strength: Sequence[float],
) -> tuple[PopulationStrength, ...]:
    """The population strength of every half-joint in ``groups`` of a body described by
    ``body`` (both sexes at its stature, mass and age). ``strength`` [N·m] is the problem's
    own strength of each group at the posture considered (``Torques.strength``): the mean of
    the body's sex. The other sex's mean is it times the ratio of the two sexes' shipped
    defaults (their values, posture-free: a curve's scale), also for a group whose strength
    the file sets (``own``: group -> where it is set); a group without a shipped default
    takes the same mean for both sexes."""
    out = []
    known = set(known_groups())
    for k, name in enumerate(groups):
        cv, sd_source, sd_status = strength_spread(data_name(name))
        given = float(strength[k])
        where = f" ({own[name]})" if name in own else " (strength.toml)"
        if data_name(name) in known:
            value = {
                sex: default_strength(
                    name,
                    sex=sex,
                    stature=body.stature_m,
                    body_mass=body.mass_kg,
                    age=body.age_years,
                )[0].value
                for sex in SEXES
            }
            mean = {sex: given * value[sex] / value[body.sex] for sex in SEXES}
            source = (
                f"the problem's strength at the posture for {PEOPLE[body.sex]}{where}, the "
                f"other sex by the ratio of the shipped defaults at {body.stature_m:g} m, "
                f"{body.mass_kg:g} kg, {body.age_years:g} y"
            )
        else:
            mean = dict.fromkeys(SEXES, given)
            source = f"the problem's own strength, for both sexes{where}"
        sd = {sex: cv[sex] * mean[sex] for sex in SEXES}
        out.append(PopulationStrength(name, mean, sd, source, sd_source, sd_status))
    return tuple(out)


def strength_spread(group: str) -> tuple[dict[Sex, float], str, SdStatus]:
    """The coefficient of variation of a group's strength per sex, its source and status:
    Anderson 2007's, pooled over its young and middle-aged rows, where it has data, else our
    estimate."""
    rows = {sex: anderson_young(group, sex) for sex in SEXES}
    male, female = rows["male"], rows["female"]
    if male is None or female is None:
        cv = population_cv()
        return (
            dict.fromkeys(SEXES, cv.value),
            f"CV {cv.value:g} × mean ({cv.source})",
            "estimate",
        )
    ratios: dict[Sex, float] = {"male": male[1], "female": female[1]}
    source = (
        f"Anderson 2007 c1 SD/mean, root mean square of the young and middle-aged rows: "
        f"male {ratios['male']:.3f}, female {ratios['female']:.3f} ({male[0].source})"
    )
    return ratios, source, "measured"


def capability(groups: Sequence[PopulationStrength], required: Sequence[float]) -> Capability:
    """The share of each sex able to exert ``required`` [N·m] per group (same order as
    ``groups``); a group that carries nothing counts as 100 %, one whose mean strength is
    not positive as 0 %."""
    out = []
    for group, tau in zip(groups, required, strict=True):
        tau = float(tau)
        shares = {sex: _share(group, sex, tau) for sex in SEXES}
        out.append(GroupCapability(group, tau, shares))
    return Capability(tuple(out))


def _share(group: PopulationStrength, sex: Sex, required: float) -> float:
    """One group's share [%]: 100 when it carries nothing, 0 when the population's mean
    strength is not positive (a regression outside its range), else ``share_capable``."""
    if required <= 0.0:
        return 100.0
    if group.mean[sex] <= 0.0:
        return 0.0
    return float(share_capable(group.mean[sex], group.sd[sex], required))
