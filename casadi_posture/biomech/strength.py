"""Joint strength: maximum voluntary torque of each half-joint, possibly posture dependent."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import casadi as ca
import numpy as np

from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter, data_name


class Strength(Protocol):
    """st(q) [N·m] of one half-joint, an expression of the whole joint vector q [rad]."""

    def expression(self, q: ca.SX) -> ca.SX: ...


def comfort_strength(model: Strength, q: ca.SX) -> ca.SX:
    """The strength [N·m] the comfort measure's effort row divides by: a constant or shipped
    curve's ``reference`` (the comfort measure's own effort scale where the shipped data set
    one, ``comfort_ratio`` in strength.toml, so that a measured strength changes the loads
    (%MVC) and the fatigue but not the balance of the comfort measure's terms); any other
    model's own st(q)."""
    if isinstance(model, ConstantStrength | ScaledCurveStrength):
        return ca.SX(model.reference)
    return model.expression(q)


@dataclass(frozen=True)
class ConstantStrength:
    """A posture-independent strength [N·m]."""

    value: float | ca.SX
    #: The fraction [-] of ``value`` the comfort measure divides by (1: the strength itself).
    comfort_fraction: float = 1.0

    @property
    def reference(self) -> float | ca.SX:
        """The constant [N·m] the comfort measure divides by: ``value`` × ``comfort_fraction``."""
        return self.value * self.comfort_fraction

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


#: Half-width [rad] over which a shipped curve's knots are rounded (3°).
KNOT_ROUNDING_RAD = math.radians(3.0)


@dataclass(frozen=True)
class ScaledCurveStrength:
    """A strength [N·m] that depends on one DOF's angle: ``value`` [N·m] (the strength at
    the first angle, a float or an expression) times a relative curve through
    (``angles`` [rad], ``fractions`` [-]), linear between them and held beyond, its knots
    rounded over about ±``KNOT_ROUNDING_RAD``: a sum of softplus hinges, exact away from the
    knots and within ln 2 · w · |change of slope| of the lines at a knot (1.1 % of the
    shoulder flexors' value), smooth so that the IK's comfort level, which weighs loads by
    strength, has derivatives everywhere. The shipped posture-dependent defaults
    (``ratio_curve`` in strength.toml)."""

    value: float | ca.SX
    dof_index: int
    angles: tuple[float, ...]
    fractions: tuple[float, ...]
    #: The curve's fraction [-] at the angle whose strength the comfort measure uses.
    comfort_fraction: float = 1.0

    @property
    def reference(self) -> float | ca.SX:
        """The constant strength [N·m] the comfort measure divides by: ``value`` times
        ``comfort_fraction``."""
        return self.value * self.comfort_fraction

    def shape(self, angle: ca.SX) -> ca.SX:
        """The relative curve [-] at ``angle`` [rad]."""
        slopes = [
            (f1 - f0) / (a1 - a0)
            for a0, a1, f0, f1 in zip(
                self.angles, self.angles[1:], self.fractions, self.fractions[1:], strict=False
            )
        ]
        changes = np.diff([0.0, *slopes, 0.0])
        w = KNOT_ROUNDING_RAD
        out = ca.SX(self.fractions[0])
        for knot, change in zip(self.angles, changes, strict=True):
            out += change * w * ca.log1p(ca.exp((angle - knot) / w))
        return out

    def expression(self, q: ca.SX) -> ca.SX:
        return self.value * self.shape(q[self.dof_index])


#: The strength tables of ``strength.toml`` that hold groups, in the order they are tried.
_GROUP_TABLES = ("ratio", "harbo_2012_groups", "anderson_2007", "estimate")
_HARBO_KEYS = ("intercept", "age", "stature", "body_mass")


def default_strength(
    half_joint: str, *, sex: str, stature: float, body_mass: float, age: float, dof_index: int = 0
) -> tuple[ConstantStrength | ScaledCurveStrength, Parameter]:
    """The default strength of a half-joint (docs/sources.md) and its provenance.

    ``half_joint`` may carry a side suffix (``shoulder_abductors_r``): the data of the name
    without it are used, the record keeps the full name. By the table the group is in:
    the elbow flexors from the Harbo et al. 2012 regression at this stature [m], body mass
    [kg] and age [years] times the group's Gymnast strength ratio; the group's own Harbo
    regression; Anderson et al. 2007 young adults' c1·m·g·h of the sex (``anderson_young``)
    or our estimate c·m·g·h, both times ``age_factor``. A group with a ``ratio_curve``
    depends on the angle of its own DOF, ``dof_index`` in q (``ScaledCurveStrength``;
    its ``value`` is the strength at the curve's first angle). The record's source shows the
    computation; a curve's record holds its (angle [deg], strength [N·m]) points.
    """
    group = data_name(half_joint)
    table = parameters.load("strength")
    comfort_fraction = 1.0
    if f"strength.ratio.{group}" in table:
        ratio = table[f"strength.ratio.{group}"]
        elbow_flexors, elbow = elbow_flexion(sex, stature, body_mass, age)
        value = elbow_flexors * ratio.value
        source = f"{elbow} × ratio {ratio.value:g} ({ratio.source})"
        evidence = "C1+E"
        if f"strength.comfort_ratio.{group}" in table:
            comfort = table[f"strength.comfort_ratio.{group}"].value
            comfort_fraction = comfort / ratio.value
            source += (
                f"; the comfort measure divides by a constant {value * comfort_fraction:.2f} "
                f"N·m (ratio {comfort:g})"
            )
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
    if f"strength.ratio_curve.{group}.angle_deg" in table:
        angles = table[f"strength.ratio_curve.{group}.angle_deg"]
        fractions = table[f"strength.ratio_curve.{group}.fraction"]

        points = [
            (a, round(value * f, 4)) for a, f in zip(angles.value, fractions.value, strict=True)
        ]
        source += (
            f"; at the angles {angles.value} deg of its DOF × {fractions.value}: "
            f"{', '.join(f'{n:.2f} N·m' for _, n in points)} ({angles.source})"
        )
        curve = ScaledCurveStrength(
            value,
            dof_index,
            tuple(math.radians(a) for a in angles.value),
            tuple(fractions.value),
            comfort_fraction,
        )
        return curve, Parameter(
            f"strength.{half_joint}", points, "[deg, N·m]", source, "estimate", evidence
        )
    record = Parameter(
        name=f"strength.{half_joint}",
        value=round(value, 4),
        unit="N·m",
        source=source,
        status="estimate",
        evidence=evidence,
    )
    return ConstantStrength(value, comfort_fraction), record


def elbow_flexion(sex: str, stature: float, body_mass: float, age: float) -> tuple[float, str]:
    """The body's isometric elbow-flexion strength [N·m], the Harbo et al. 2012 regression of
    ``sex`` at ``stature`` [m], ``body_mass`` [kg] and ``age`` [years] that the ratio groups
    scale, and the computation in words."""
    value = _harbo("harbo_2012", sex, stature, body_mass, age)[0]
    words = (
        f"Harbo 2012 elbow-flexion regression ({sex}, {age:g} y, {stature:g} m, "
        f"{body_mass:g} kg) = {value:.2f} N·m"
    )
    return value, words


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
