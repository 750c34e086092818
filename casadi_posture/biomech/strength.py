"""Joint strength: maximum voluntary torque of each half-joint, possibly posture dependent."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import casadi as ca

from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter, data_name


class Strength(Protocol):
    """st(q) [N·m] of one half-joint, an expression of the whole joint vector q [rad]."""

    def expression(self, q: ca.SX) -> ca.SX: ...


@dataclass(frozen=True)
class ConstantStrength:
    """A posture-independent strength [N·m]."""

    value: float

    def expression(self, q: ca.SX) -> ca.SX:
        return ca.SX(self.value)


@dataclass(frozen=True)
class TabulatedStrength:
    """Strength interpolated linearly in one DOF's angle, held constant beyond the table.

    ``angles`` [rad] strictly increasing, ``values`` [N·m], ``dof_index`` the
    DOF whose angle it depends on (e.g. 3DSSPP-style curves entered by the user).
    """

    dof_index: int
    angles: tuple[float, ...]
    values: tuple[float, ...]

    def expression(self, q: ca.SX) -> ca.SX:
        angle = ca.fmin(ca.fmax(q[self.dof_index], self.angles[0]), self.angles[-1])
        return ca.pw_lin(angle, ca.DM(self.angles), ca.DM(self.values))


#: The strength tables of ``strength.toml`` that hold groups, in the order they are tried.
_GROUP_TABLES = ("ratio", "harbo_2012_groups", "anderson_2007", "estimate")
_HARBO_KEYS = ("intercept", "age", "stature", "body_mass")


def default_strength(
    half_joint: str, *, sex: str, stature: float, body_mass: float, age: float
) -> tuple[ConstantStrength, Parameter]:
    """The default strength of a half-joint (docs/sources.md) and its provenance.

    ``half_joint`` may carry a side suffix (``shoulder_abductors_r``): the data of the name
    without it are used, the record keeps the full name. By the table the group is in:
    the elbow flexors from the Harbo et al. 2012 regression at this stature [m], body mass
    [kg] and age [years] times the group's Gymnast strength ratio; the group's own Harbo
    regression; Anderson et al. 2007 young adults' c1·m·g·h of the sex (``anderson_young``)
    or our estimate c·m·g·h, both times ``age_factor``. The record's source shows the
    computation.
    """
    group = data_name(half_joint)
    table = parameters.load("strength")
    if f"strength.ratio.{group}" in table:
        ratio = table[f"strength.ratio.{group}"]
        elbow_flexors = _harbo("harbo_2012", sex, stature, body_mass, age)[0]
        value = elbow_flexors * ratio.value
        source = (
            f"Harbo 2012 elbow-flexion regression ({sex}, {age:g} y, {stature:g} m, "
            f"{body_mass:g} kg) = {elbow_flexors:.2f} N·m × ratio {ratio.value:g} ({ratio.source})"
        )
        evidence = "C1+E"
    elif f"strength.harbo_2012_groups.{group}.{sex}.intercept" in table:
        value, c, record = _harbo(f"harbo_2012_groups.{group}", sex, stature, body_mass, age)
        source = (
            f"Harbo 2012 regression ({sex}): {c['intercept']:g} + ({c['age']:g})·{age:g} y"
            f" + {c['stature']:g}·{stature:g} m + {c['body_mass']:g}·{body_mass:g} kg"
            f" = {value:.2f} N·m ({record.source})"
        )
        evidence = record.evidence
    elif (young := anderson_young(group, sex)) is not None:
        c1, cv = young
        factor, rule = age_factor(sex, age)
        g = table["strength.anderson_2007.gravity"].value
        value = c1.value * body_mass * g * stature * factor
        source = (
            f"Anderson 2007 young adults' c1·m·g·h × age factor ({sex}): {c1.value:g} × "
            f"{body_mass:g} kg × {g:g} m/s² × {stature:g} m × {factor:.4f} = {value:.2f} N·m "
            f"({rule}); CV {cv:.3f} ({c1.source})"
        )
        evidence = c1.evidence
    else:
        record = table[f"strength.estimate.{group}.c"]
        factor, rule = age_factor(sex, age)
        g = table["strength.anderson_2007.gravity"].value
        value = record.value * body_mass * g * stature * factor
        source = (
            f"c·m·g·h × age factor: {record.value:g} × {body_mass:g} kg × {g:g} m/s² × "
            f"{stature:g} m × {factor:.4f} = {value:.2f} N·m ({record.source}; {rule})"
        )
        evidence = record.evidence
    record = Parameter(
        name=f"strength.{half_joint}",
        value=round(value, 4),
        unit="N·m",
        source=source,
        status="estimate",
        evidence=evidence,
    )
    return ConstantStrength(value), record


def _harbo(
    prefix: str, sex: str, stature: float, body_mass: float, age: float
) -> tuple[float, dict[str, float], Parameter]:
    """A Harbo et al. 2012 regression ``strength.<prefix>.<sex>``: its value [N·m], its
    coefficients and the record of its intercept (source, evidence)."""
    table = parameters.load("strength")
    c = {k: table[f"strength.{prefix}.{sex}.{k}"].value for k in _HARBO_KEYS}
    value = c["intercept"] + c["age"] * age + c["stature"] * stature + c["body_mass"] * body_mass
    return value, c, table[f"strength.{prefix}.{sex}.intercept"]


#: Records of the ``anderson_2007`` table that are not muscle groups.
_ANDERSON_SETTINGS = ("gravity",)
#: Anderson 2007's rows whose SDs make the population's spread (its older row: 3 people a sex).
_POOLED_ROWS = ("young", "middle_aged")
_AGE_KEYS = ("reference_years", "breakpoint_years", "pct_per_year_before", "pct_per_year_after")


def age_factor(sex: str, age: float) -> tuple[float, str]:
    """The strength at ``age`` [years] as a fraction of the young adult's, for ``sex``
    (``strength.age_decline``: 1 up to the reference age, then falling linearly, at one
    rate up to the breakpoint and another beyond), and the rule in words."""
    table = parameters.load("strength")
    c = {k: table[f"strength.age_decline.{sex}.{k}"].value for k in _AGE_KEYS}
    start, knee = c["reference_years"], c["breakpoint_years"]
    before = min(max(age, start), knee) - start
    after = max(age - knee, 0.0)
    factor = 1.0 - (c["pct_per_year_before"] * before + c["pct_per_year_after"] * after) / 100.0
    rule = (
        f"age {age:g} y: 1 to {start:g} y, −{c['pct_per_year_before']:g} %/year to {knee:g} y, "
        f"−{c['pct_per_year_after']:g} %/year beyond"
    )
    return factor, rule


def anderson_young(group: str, sex: str) -> tuple[Parameter, float] | None:
    """Anderson 2007's young adults' ``c1`` record of ``group`` (a name without side suffix)
    for ``sex`` and the group's coefficient of variation, pooled over the young and
    middle-aged rows (root mean square of c1_sd/c1); None when the group has no data."""
    table = parameters.load("strength")
    prefix = f"strength.anderson_2007.{group}.{sex}"
    if f"{prefix}.young.c1" not in table:
        return None
    ratios = [
        table[f"{prefix}.{row}.c1_sd"].value / table[f"{prefix}.{row}.c1"].value
        for row in _POOLED_ROWS
    ]
    return table[f"{prefix}.young.c1"], math.sqrt(sum(r * r for r in ratios) / len(ratios))


def known_groups() -> Sequence[str]:
    """Half-joints with a shipped default strength (names without a side suffix)."""
    groups: dict[str, None] = {}
    for name in parameters.load("strength"):
        parts = name.split(".")  # strength.<table>.<group>...
        if len(parts) > 2 and parts[1] in _GROUP_TABLES and parts[2] not in _ANDERSON_SETTINGS:
            groups.setdefault(parts[2], None)
    return list(groups)
