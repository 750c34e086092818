"""docs/strength.md: the shipped strength's age terms as the package computes them
(``strength-age``)."""

from __future__ import annotations

from typing import Any

from casadi_posture.biomech.strength import age_factor, elbow_flexion
from casadi_posture.spec.schema import BodySpec

from .regions import Region
from .session import Session

#: The ages [years] the page quotes.
AGES = (25, 30, 40, 50, 52, 60, 62, 75)
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
    }
