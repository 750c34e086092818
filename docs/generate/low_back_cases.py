"""docs/low_back.md, "Checked against": two published worked calculations of the single
equivalent muscle model, reproduced on their own geometry and on the ``upper_body`` of
the seated problems (``low-back-cases``). The sources' inputs are quoted here; every
number of ours is computed by ``LowBackModel``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

import casadi_posture as cp
from casadi_posture.biomech.low_back import LowBack, LowBackModel
from casadi_posture.body.loads import Load
from casadi_posture.body.tree import BodyModel, Dof, Landmark, Segment

from .regions import Region
from .session import ROOT, Session

#: Gravity [m/s²], as the sources take it.
G = 9.81
#: The problem whose body (``upper_body``) stands for ours.
BODY_PROBLEM = "seated_assembly"
#: Bisection steps for a shoulder flexion [deg] (90° / 2⁴⁰).
STEPS = 40


@dataclass(frozen=True)
class Case:
    """A published case: the subject's ``mass_kg``, the trunk's flexion from vertical
    [deg], the ``load`` in the hands [N], the weight above the disc the source takes
    (load excluded: ``upper`` [N] at ``upper_m`` ahead of L5/S1) and the load's distance
    ahead ``load_m`` [m] (the lab's: everything lumped, the load included, in ``upper``,
    at ``upper_m``), and what our arms must match on our body: the hands' distance ahead
    [m] (``hands_m``) or the ``moment`` [N·m]."""

    mass_kg: float
    trunk_deg: float
    load: float
    upper: float
    upper_m: float
    load_m: float = 0.0
    hands_m: float | None = None
    moment: float | None = None


#: homeworksource p/1067204: upper body 450 N at 0.25 m, 200 N at 0.40 m, trunk 35°.
WORKED = Case(73.0, 35.0, 200.0, 450.0, 0.25, 0.40, hands_m=0.40)
#: The lifting lab: 20 kg stoop lift, its moment 250.3 N·m; its split C − F_m = 306.3 N
#: (= W cos θ) and S = 530.49 N (= W sin θ) give the weight W and the angle θ.
LAB_SPLIT_N = (5312.3 - 5006.0, 530.49)
LAB = Case(
    81.14,
    float(np.degrees(np.arctan2(LAB_SPLIT_N[1], LAB_SPLIT_N[0]))),
    20.0 * G,
    float(np.hypot(*LAB_SPLIT_N)),
    250.3 / float(np.hypot(*LAB_SPLIT_N)),
    moment=250.3,
)


def own_geometry(case: Case) -> LowBack:
    """The case on its own geometry: one lumbar flexion DOF carrying the source's weight
    and load at their distances ahead of L5/S1 at the case's trunk angle."""
    theta = np.radians(case.trunk_deg)
    along = [arm / np.sin(theta) for arm in (case.upper_m, case.load_m or case.upper_m)]
    dof = Dof("lumbar_flexion", None, (0, 0, 1), (0, 1, 0), -1.0, 2.0, "flexors", "extensors")
    body = BodyModel(
        "lumped",
        [dof],
        [Segment("above", "lumbar_flexion", case.upper / G, (0.0, 0.0, 1.0 + along[0]))],
        [Landmark("hands", "lumbar_flexion", (0.0, 0.0, 1.0 + along[1]))],
        gravity=G,
    )
    loads = [Load("load", "hands", mass=case.load / G)] if case.load_m else []
    return LowBackModel(body, loads).evaluate([theta])


class OurBody:
    """``upper_body`` of a subject of ``case.mass_kg`` flexed by the case's trunk angle,
    the load shared by the two grips."""

    def __init__(self, case: Case) -> None:
        problem = cp.load(
            ROOT / "problems" / f"{BODY_PROBLEM}.toml", {"body.mass_kg": case.mass_kg}
        )
        self.case, self.body = case, problem.body
        grips = [Load(side, f"grip_{side}", mass=case.load / G / 2) for side in "rl"]
        self.loaded, self.bare = LowBackModel(self.body, grips), LowBackModel(self.body, [])

    def posture(self, shoulder_deg: float) -> np.ndarray:
        """The trunk flexed, both shoulders flexed ``shoulder_deg`` from the trunk [rad]."""
        q = np.zeros(self.body.n)
        q[self.body.index["lumbar_flexion"]] = np.radians(self.case.trunk_deg)
        for side in "rl":
            q[self.body.index[f"shoulder_flexion_{side}"]] = np.radians(shoulder_deg)
        return q

    def hands_m(self, shoulder_deg: float) -> float:
        """How far ahead of L5/S1 the hands are [m]: the load's moment over its weight."""
        q = self.posture(shoulder_deg)
        extra = self.loaded.evaluate(q).sagittal_moment - self.bare.evaluate(q).sagittal_moment
        return extra / self.case.load

    def matched(self) -> float:
        """The shoulder flexion [deg] at which the hands are as far ahead as the case's, or
        the moment is the case's, by bisection from arms hanging to arms level."""
        case, low, high = self.case, self.case.trunk_deg, self.case.trunk_deg + 90.0
        for _ in range(STEPS):
            mid = 0.5 * (low + high)
            short = (
                self.hands_m(mid) < case.hands_m
                if case.hands_m is not None
                else self.loaded.evaluate(self.posture(mid)).sagittal_moment < case.moment
            )
            low, high = (mid, high) if short else (low, mid)
        return 0.5 * (low + high)

    def facts(self) -> dict[str, Any]:
        """``above_N``: the weight above the disc (load excluded) [N], ``com_m`` its
        distance ahead [m]; ``hanging`` and ``matched``: the low back with the arms hanging
        (shoulder flexion = trunk flexion) and with the arms as the case's, and each's
        ``*_hands_m``; ``shoulder_deg`` the matched shoulder flexion from the trunk."""
        hanging, shoulder = self.case.trunk_deg, self.matched()
        bare = self.bare.evaluate(self.posture(hanging))
        above = (bare.compression - bare.muscle_force) / np.cos(np.radians(self.case.trunk_deg))
        return {
            "above_N": above,
            "com_m": bare.sagittal_moment / above,
            "hanging": self.loaded.evaluate(self.posture(hanging)),
            "hanging_hands_m": self.hands_m(hanging),
            "matched": self.loaded.evaluate(self.posture(shoulder)),
            "matched_hands_m": self.hands_m(shoulder),
            "shoulder_deg": shoulder,
        }


def case_values(case: Case) -> dict[str, Any]:
    """:meth:`OurBody.facts` of the case, ``own`` (:func:`own_geometry`), the case's
    ``upper_N``, ``trunk_deg`` and ``load_N`` (its inputs), and the differences at the matched arms:
    ``less_moment_Nm``, ``less_compression_N`` (theirs − ours), ``with_load_N`` (our
    weight above the disc, load included), ``less_weight_N`` (theirs − ours) and
    ``less_weight_cos_N`` (times cos θ)."""
    ours = OurBody(case).facts()
    own = own_geometry(case)
    matched = ours["matched"]
    lumped = case.upper + (case.load if case.load_m else 0.0)
    less_weight = lumped - ours["above_N"] - case.load
    return ours | {
        "own": own,
        "upper_N": case.upper,
        "trunk_deg": case.trunk_deg,
        "load_N": case.load,
        "less_moment_Nm": own.sagittal_moment - matched.sagittal_moment,
        "less_compression_N": own.compression - matched.compression,
        "with_load_N": ours["above_N"] + case.load,
        "less_weight_N": less_weight,
        "less_weight_cos_N": less_weight * np.cos(np.radians(case.trunk_deg)),
    }


def values(region: Region, session: Session) -> dict[str, Any]:
    """``worked`` and ``lab``: :func:`case_values` of the two published cases."""
    return {"worked": case_values(WORKED), "lab": case_values(LAB)}
