"""docs/strength.md: the shipped strengths of the reference man and woman (``strengths``)
and their age terms (``strength-age``), as the package computes them."""

from __future__ import annotations

import math
from typing import Any

import casadi_posture as cp
from casadi_posture.biomech.strength import (
    age_factor,
    anderson_young,
    default_strength,
    elbow_flexion,
    known_groups,
)
from casadi_posture.data import parameters
from casadi_posture.spec.schema import BodySpec

from .regions import Region
from .session import ROOT, Session

#: The ages [years] the page quotes.
AGES = (25, 30, 40, 50, 52, 60, 62, 70, 75)
#: The default body, whose Harbo elbow flexion the page quotes: stature [m], mass [kg].
REFERENCE = tuple(BodySpec.model_fields[k].default for k in ("stature_m", "mass_kg"))


def values(region: Region, session: Session) -> dict[str, Any]:
    """``factor[SEX][AGE]``: the strength at AGE [years] as a fraction of the young
    adult's (``strength.age_decline``) and ``elbow[SEX][AGE]``: the Harbo elbow-flexion
    strength [N·m] of the default body (:data:`REFERENCE`) at that age, for the ages
    :data:`AGES`, and ``pct``, the same in %; ``loss_male_pct`` and ``loss_female_pct``: the
    share of the young value lost in the decade past each sex's knee in the decline (52
    and 40 y) [%], ``elbow_pct``: a man's Harbo elbow flexion at 50 y over his at 30 y [%]."""
    sexes = ("male", "female")
    factor = {s: {a: age_factor(s, a)[0] for a in AGES} for s in sexes}
    elbow = {s: {a: elbow_flexion(s, *REFERENCE, a)[0] for a in AGES} for s in sexes}
    return {
        "factor": factor,
        "pct": {s: {a: 100 * f for a, f in by_age.items()} for s, by_age in factor.items()},
        "elbow": elbow,
        "loss_male_pct": 100 * (factor["male"][52] - factor["male"][62]),
        "loss_female_pct": 100 * (factor["female"][40] - factor["female"][50]),
        "elbow_pct": 100 * elbow["male"][50] / elbow["male"][30],
        "knee_female": {
            row: _anderson("knee_extensors", "female", row) for row in ("young", "older")
        },
    } | spread()


#: How the page names a sex's groups.
WHOSE = {"male": "men's", "female": "women's"}


def _anderson(group: str, sex: str, row: str) -> tuple[float, float]:
    """Anderson 2007's ``c1`` and its SD for ``group``, ``sex`` and age ``row``."""
    table = parameters.load("strength")
    prefix = f"strength.anderson_2007.{group}.{sex}.{row}"
    return table[f"{prefix}.c1"].value, table[f"{prefix}.c1_sd"].value


def spread() -> dict[str, Any]:
    """``cv_low`` and ``cv_high``: the least and greatest pooled CV of a group with
    Anderson's data, each with ``who`` (the sex's group, as the page names it);
    ``cv_older``, the least and greatest CV of his older rows; ``cv_estimate``, the CV of
    every other group (``strength.population_cv``)."""
    groups = [g for g in known_groups() if anderson_young(g, "male") is not None]
    pooled = [
        (anderson_young(g, sex)[1], f"{WHOSE[sex]} {g.replace('_', ' ')}")
        for g in groups
        for sex in WHOSE
    ]
    older = [sd / c1 for g in groups for sex in WHOSE for c1, sd in [_anderson(g, sex, "older")]]
    low, high = min(pooled), max(pooled)
    return {
        "cv_low": {"value": low[0], "who": low[1]},
        "cv_high": {"value": high[0], "who": high[1]},
        "cv_older": (min(older), max(older)),
        "cv_estimate": parameters.value("strength", "population_cv"),
    }


def reference(sex: str) -> tuple[float, float]:
    """De Leva's reference ``sex``: stature [m] and body mass [kg]."""
    table = parameters.load("anthropometry_de_leva_1996")
    prefix = f"anthropometry_de_leva_1996.{sex}.reference"
    return table[f"{prefix}.stature"].value, table[f"{prefix}.body_mass"].value


def group_strength(group: str, sex: str, age: float) -> float | dict[int, float]:
    """The default strength [N·m] of ``group`` for de Leva's reference ``sex`` at ``age``
    [years]; a curve's at each of its knots, by angle [deg]."""
    stature, mass = reference(sex)
    model, _ = default_strength(group, sex=sex, stature=stature, body_mass=mass, age=age)
    if hasattr(model, "fractions"):
        return {
            round(math.degrees(a)): float(model.value) * f
            for a, f in zip(model.angles, model.fractions, strict=True)
        }
    return float(model.value)


def comfort_ratio(group: str) -> float | None:
    """The comfort measure's effort scale of ``group``: its ratio to elbow flexion
    (``strength.comfort_ratio``), the constant strength the group had before its measured
    one; None for a group the measure scales by its strength."""
    found = parameters.load("strength").get(f"strength.comfort_ratio.{group}")
    return None if found is None else found.value


def earlier(group: str, sex: str, age: float = 30) -> float:
    """The group's earlier constant strength [N·m] (:func:`comfort_ratio` × elbow flexion)
    for de Leva's reference ``sex``."""
    return comfort_ratio(group) * group_strength("elbow_flexors", sex, age)


def strengths(region: Region, session: Session) -> dict[str, Any]:
    """``man[GROUP]`` and ``woman[GROUP]``: the default strength [N·m] of each group of
    ``groups=`` (comma-separated) for de Leva's reference man and woman at 30 y, a curve's
    by its knots' angles [deg] (``{man[shoulder_flexors][45]:.1f}``); ``man25``: at 25 y;
    ``ratio[GROUP]``: the group's ratio to elbow flexion (``strength.ratio``), and for the
    groups the comfort measure scales by its own constant, ``comfort[GROUP]`` (that
    constant's ratio) and ``earlier[man|woman][GROUP]`` (the constant strength [N·m])."""
    groups = region.args["groups"].split(",")
    people = {"man": ("male", 30), "woman": ("female", 30), "man25": ("male", 25)}
    table = parameters.load("strength")
    comfort = {g: comfort_ratio(g) for g in groups if comfort_ratio(g) is not None}
    return {
        name: {g: group_strength(g, sex, age) for g in groups}
        for name, (sex, age) in people.items()
    } | {
        "ratio": {
            g: table[f"strength.ratio.{g}"].value for g in groups if f"strength.ratio.{g}" in table
        },
        "comfort": comfort,
        "earlier": {
            n: {g: earlier(g, sex) for g in comfort}
            for n, sex in (("man", "male"), ("woman", "female"))
        },
        "reading": readings(),
    }


#: Published values the Reading column sets ours beside (quotations): the rotator study's
#: men and women (age [y], stature [m], mass [kg]), Harbo's isokinetic elbow extension of
#: the reference man [N·m], the one ulnar-deviation measurement [N·m] and Rantanen's
#: women's lumbar extension with the axis at the posterior iliac spines [N·m].
ROTATOR_STUDY = {"male": (22, 1.785, 85.4), "female": (21, 1.685, 70.1)}
HARBO_ISOKINETIC_EXTENSION_NM = 45.1
ULNAR_MEASURED_NM = 9.5
RANTANEN_WOMEN_NM = 182.0
#: The published isokinetic elbow extension : flexion ratios (Lategan & Krüger; Harbo).
EXTENSION_RATIOS = (0.84, 0.90)


def readings() -> dict[str, Any]:
    """The figures the Reading column derives from our strengths: ``ext_flex`` (extensors
    over flexors at 0° and 90° of flexion), ``harbo_study`` (the rotator study's men's
    Harbo elbow flexion [N·m]), ``study_woman`` (internal and external rotators of a woman
    of that study's size [N·m]), ``int_ext`` and ``int_ext_earlier`` (internal over
    external rotators, now and before), ``women_ext_pct`` (women's external rotators over
    men's [%]), ``elbow_ext_range`` (the extensors at :data:`EXTENSION_RATIOS` × elbow
    flexion [N·m] by sex), ``isokinetic_above_pct``, ``ulnar_above_pct``,
    ``pron_men_women`` and ``lumbar_under_pct`` (ours against the quoted values [%]) and
    ``arm_horizontal_pct``: :func:`arm_horizontal_torque` over the flexors at 90° [%]."""
    man = {g: group_strength(g, "male", 30) for g in GROUPS}
    woman = {g: group_strength(g, "female", 30) for g in GROUPS}
    flexors = man["shoulder_flexors"]
    table = parameters.load("strength")
    rotators = ("shoulder_internal_rotators", "shoulder_external_rotators")
    ratio = [table[f"strength.ratio.{g}"].value for g in rotators]
    woman_study = elbow_flexion("female", *_size(ROTATOR_STUDY["female"]))[0]
    return {
        "ext_flex": {a: man["shoulder_extensors"] / flexors[a] for a in (0, 90)},
        "harbo_study": elbow_flexion("male", *_size(ROTATOR_STUDY["male"]))[0],
        "study_woman": [r * woman_study for r in ratio],
        "int_ext": man[rotators[0]] / man[rotators[1]],
        "int_ext_earlier": earlier(rotators[0], "male") / earlier(rotators[1], "male"),
        "women_ext_pct": 100 * woman[rotators[1]] / man[rotators[1]],
        "elbow_ext_range": {
            who: [r * by["elbow_flexors"] for r in EXTENSION_RATIOS]
            for who, by in (("man", man), ("woman", woman))
        },
        "isokinetic_above_pct": 100 * (HARBO_ISOKINETIC_EXTENSION_NM / man["elbow_extensors"] - 1),
        "ulnar_above_pct": 100 * (man["wrist_ulnar_deviators"] / ULNAR_MEASURED_NM - 1),
        "pron_men_women": man["forearm_pronators"] / woman["forearm_pronators"],
        "lumbar_under_pct": 100 * (1 - woman["lumbar_extensors"] / RANTANEN_WOMEN_NM),
        "arm_horizontal_pct": 100 * arm_horizontal_torque() / flexors[90],
    }


def arm_horizontal_torque() -> float:
    """The shoulder flexors' torque [N·m] holding the reference man's unloaded right arm
    straight out in front (the standing body, every other DOF at 0°)."""
    path = ROOT / "problems" / "standing_wall_horizontal.toml"
    problem = cp.load(path, {"loads[0].mass_kg": 0.0})
    posture = dict.fromkeys(problem.body.index, 0.0) | {"shoulder_flexion_r": 90.0}
    groups = cp.torques(problem, posture_deg=posture).to_frame().set_index("name")
    return float(groups.loc["shoulder_flexors_r", "torque_Nm"])


#: The groups :func:`readings` compares.
GROUPS = (
    "shoulder_flexors",
    "shoulder_extensors",
    "shoulder_internal_rotators",
    "shoulder_external_rotators",
    "elbow_flexors",
    "elbow_extensors",
    "wrist_ulnar_deviators",
    "forearm_pronators",
    "lumbar_extensors",
)


def _size(person: tuple[float, float, float]) -> tuple[float, float, float]:
    """(age, stature, mass) → the (stature, mass, age) :func:`elbow_flexion` takes."""
    age, stature, mass = person
    return stature, mass, age
