"""Joint strength: maximum voluntary torque of each half-joint, possibly posture dependent."""

from __future__ import annotations

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
    regression; Anderson et al. 2007 c1·m·g·h of the sex and age group (:func:`anderson_row`);
    or our estimate c·m·g·h. The record's source shows the computation.
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
    elif (row := anderson_row(group, sex, age)) is not None:
        record, sd_record, rule = row
        sd = sd_record.value
        g = table["strength.anderson_2007.gravity"].value
        mgh = body_mass * g * stature
        value = record.value * mgh
        source = (
            f"Anderson 2007 c1·m·g·h ({sex}, {rule}): {record.value:g} × "
            f"{body_mass:g} kg × {g:g} m/s² × {stature:g} m = {value:.2f} N·m; "
            f"SD {sd:g} × m·g·h = {sd * mgh:.2f} N·m ({record.source})"
        )
        evidence = record.evidence
    else:
        record = table[f"strength.estimate.{group}.c"]
        g = table["strength.anderson_2007.gravity"].value
        value = record.value * body_mass * g * stature
        source = (
            f"c·m·g·h: {record.value:g} × {body_mass:g} kg × {g:g} m/s² × {stature:g} m"
            f" = {value:.2f} N·m ({record.source})"
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


#: Anderson 2007's age groups: our name and the ages of its sample.
ANDERSON_AGE_GROUPS = {"young": "18-25 y", "middle_aged": "55-65 y", "older": "> 65 y"}
#: Records of the ``anderson_2007`` table that are not muscle groups.
_ANDERSON_SETTINGS = ("gravity", "middle_aged_from_years", "older_above_years")


def anderson_age_group(age: float) -> tuple[str, str]:
    """The Anderson 2007 age group for a body of ``age`` [years], and the rule in words:
    young below ``middle_aged_from_years`` (40), middle-aged up to ``older_above_years``
    (65), older above (``strength.toml``)."""
    table = parameters.load("strength")
    middle = table["strength.anderson_2007.middle_aged_from_years"].value
    older = table["strength.anderson_2007.older_above_years"].value
    name = "young" if age < middle else "middle_aged" if age <= older else "older"
    rule = (
        f"age {age:g} y: the {name.replace('_', '-')} row ({ANDERSON_AGE_GROUPS[name]}; "
        f"rule: < {middle:g} y young, {middle:g}-{older:g} y middle-aged, > {older:g} y older)"
    )
    return name, rule


def anderson_row(group: str, sex: str, age: float) -> tuple[Parameter, Parameter, str] | None:
    """The Anderson 2007 records ``c1`` and ``c1_sd`` of ``group`` (a name without side
    suffix) for ``sex`` at ``age`` [years], and the age rule in words; None when the group has
    no Anderson data."""
    name, rule = anderson_age_group(age)
    prefix = f"strength.anderson_2007.{group}.{sex}.{name}"
    table = parameters.load("strength")
    if f"{prefix}.c1" not in table:
        return None
    return table[f"{prefix}.c1"], table[f"{prefix}.c1_sd"], rule


def known_groups() -> Sequence[str]:
    """Half-joints with a shipped default strength (names without a side suffix)."""
    groups: dict[str, None] = {}
    for name in parameters.load("strength"):
        parts = name.split(".")  # strength.<table>.<group>...
        if len(parts) > 2 and parts[1] in _GROUP_TABLES and parts[2] not in _ANDERSON_SETTINGS:
            groups.setdefault(parts[2], None)
    return list(groups)
