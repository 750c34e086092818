"""RULA and REBA of a posture of our bodies: the worksheets' inputs measured from the joint
angles and the forward kinematics, per side, with every input the body or the problem does
not give taken from ``Assumptions`` and named in the result (docs/rula_reba.md).

What is measured, on the 3-D bodies (``standing``, ``upper_body``):

- trunk flexion: the angle of the thorax's long axis (L5/S1 → C7) from the vertical, in the
  trunk's own sagittal plane (forward +), from the forward kinematics — on ``standing`` it
  includes the legs' and the pelvis's tilt; twisted / side-bent: ``lumbar_rotation`` /
  ``lumbar_bending`` beyond the plausibility report's ``trunk_twist`` angle;
- upper arm: the angle between the upper arm (shoulder → elbow centre) and the trunk's
  downward axis, negative (extension) when the elbow lies more behind the shoulder than
  beside it; abducted:
  ``shoulder_abduction`` beyond ``arm_abducted`` (REBA also counts ``shoulder_rotation``
  beyond it as rotated);
- lower arm: ``elbow_flexion``; across the midline or out to the side: the wrist centre on
  the other side of the trunk's midplane, or more than ``out_to_side`` outside the shoulder;
- wrist: ``wrist_flexion``; deviated: ``wrist_deviation`` beyond the neutral tolerance;
  twist at the end of its range: ``forearm_pronation`` within the plausibility report's
  near-limit zone;
- knees (REBA, ``standing``): the larger ``knee_flexion``.

The bodies have no neck (the head rides on the thorax), no shoulder girdle and no grip: the
neck, a raised shoulder, a supported arm, the coupling, the legs' support and the activity
are assumed. The planar ``sagittal_arm`` scores its shoulder and elbow angles and
``frontal_elbow`` its elbow, its upper arm fixed at 90° of abduction; all the rest of those
two is assumed."""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture.body.loads import Load
from casadi_posture.body.tree import BodyModel
from casadi_posture.compiled import Compiled
from casadi_posture.data import parameters
from casadi_posture.ergonomics import reba, rula
from casadi_posture.ergonomics.reba import Coupling
from casadi_posture.ergonomics.rula import value
from casadi_posture.spec.schema import ErgonomicsSpec

_G = 9.80665


@dataclass(frozen=True)
class Assumptions:
    """What the body or the problem does not say, with the default used: the neck's
    flexion [deg] and twist (the head rides on the trunk), a raised shoulder, an arm
    supported, the grip's coupling, the legs supported and balanced, the posture held
    statically (> 1 min), repeated or changing rapidly, a shock in the load. ``given``
    names the fields a problem file set: they are not listed as assumed."""

    neck_deg: float = 0.0
    neck_twisted: bool = False
    shoulder_raised: bool = False
    arm_supported: bool = False
    coupling: Coupling = "good"
    legs_supported: bool = True
    static: bool = True
    repeated: bool = False
    rapid_changes: bool = False
    shock: bool = False
    given: frozenset[str] = frozenset()

    @classmethod
    def of(cls, spec: ErgonomicsSpec) -> Assumptions:
        """A problem file's ``[ergonomics]`` keys, the documented defaults for the rest."""
        given = spec.given()
        return cls(**given, given=frozenset(given))

    def assumed(self, labels: dict[str, tuple[str, ...]]) -> tuple[str, ...]:
        """The ``labels`` whose fields were not all given."""
        return tuple(label for label, keys in labels.items() if not set(keys) <= self.given)


@dataclass(frozen=True)
class SideScores:
    """RULA and REBA of one side: the worksheets' inputs, their results, and the inputs that
    were assumed rather than measured."""

    side: str
    rula_inputs: rula.RulaInputs
    rula: rula.RulaResult
    reba_inputs: reba.RebaInputs
    reba: reba.RebaResult
    assumed: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict[str, Any]:
        """Plain data: inputs (angles in degrees), every score, and the assumed inputs."""
        return {
            "side": self.side,
            "rula": {**self.rula.to_dict(), "inputs": self.rula_inputs.__dict__},
            "reba": {**self.reba.to_dict(), "inputs": self.reba_inputs.__dict__},
            "assumed": list(self.assumed),
        }


@dataclass(frozen=True)
class _Measured:
    """The worksheet angles [deg] and flags one side's posture gives."""

    upper_arm: float
    lower_arm: float
    wrist: float = 0.0
    trunk: float = 0.0
    knee: float = 0.0
    abducted: bool = False
    rotated: bool = False
    across_or_out: bool = False
    deviated: bool = False
    twist_at_end: bool = False
    trunk_twisted: bool = False
    trunk_side_bent: bool = False
    seated: bool = False


def score_posture(
    body: BodyModel,
    q: Sequence[float] | np.ndarray,
    loads: Sequence[Load] = (),
    assumptions: Assumptions = Assumptions(),
) -> list[SideScores]:
    """RULA and REBA of posture ``q`` [rad] of ``body`` holding ``loads``, per side (``r``,
    ``l``; ``arm`` for a planar body). RULA's load is what that side's hand holds; REBA's is
    every load's total (the trunk carries them all); a force counts as its size / g [kg]."""
    q = np.asarray(q, dtype=float)
    kind, assumed = body_kind(body), assumptions.assumed(_ASSUMED)
    if kind == "frontal":
        sides = {"arm": _frontal(q)}
        assumed = (*assumed, *_PLANAR, "upper arm fixed at 90° abduction by the model")
    elif kind == "sagittal":
        sides = {"arm": _sagittal(body, q)}
        assumed = (*assumed, *_PLANAR)
    elif kind == "human":
        sides = {s: _human(body, q, s) for s in ("r", "l")}
        assumed = (*assumed, *(("legs (seated)",) if sides["r"].seated else ()))
    else:
        raise ValueError(f"body {body.name!r}: {NOT_SCORED}")
    total = sum(_kg(load) for load in loads)
    out = []
    for side, m in sides.items():
        held = sum(_kg(load) for load in loads if _side(load.at) in (side, "arm"))
        out.append(_scores(side, m, held, total, assumptions, assumed))
    return out


#: Why a body gets no RULA/REBA.
NOT_SCORED = "RULA/REBA need a 3-D human (standing, upper_body) or a planar arm"


def body_kind(body: BodyModel) -> str | None:
    """How ``body`` is scored: ``frontal`` or ``sagittal`` (a planar arm), ``human`` (a 3-D
    human's DOFs and the arm landmarks the worksheets measure), None when it cannot be."""
    names = set(body.dof_names)
    if body.name == "frontal_elbow" or names == {"elbow_flexion"}:
        return "frontal"
    if names == {"shoulder_flexion", "elbow_flexion"}:
        return "sagittal"
    arms = {f"{point}_{side}" for point in ("shoulder", "elbow", "wrist") for side in "rl"}
    dofs = {"lumbar_flexion", "shoulder_flexion_r", "elbow_flexion_r"}
    if dofs <= names and arms <= set(body.landmarks):
        return "human"
    return None


#: The assumed inputs, each with the ``Assumptions`` fields a problem file sets it by.
_ASSUMED = {
    "neck": ("neck_deg", "neck_twisted"),
    "shoulder raised": ("shoulder_raised",),
    "arm supported": ("arm_supported",),
    "coupling": ("coupling",),
    "muscle use / activity": ("static", "repeated", "rapid_changes"),
    "shock": ("shock",),
    "legs supported and balanced": ("legs_supported",),
}
_PLANAR = ("trunk upright", "wrist neutral", "wrist twist mid-range")


def _kg(load: Load) -> float:
    return float(load.mass + np.linalg.norm(load.force) / _G)


def _side(landmark: str) -> str:
    return landmark[-1] if landmark.endswith(("_r", "_l")) else "arm"


def _scores(
    side: str, m: _Measured, held: float, total: float, a: Assumptions, assumed: tuple[str, ...]
) -> SideScores:
    rula_in = rula.RulaInputs(
        upper_arm_deg=m.upper_arm,
        lower_arm_deg=m.lower_arm,
        wrist_deg=m.wrist,
        shoulder_raised=a.shoulder_raised,
        arm_abducted=m.abducted,
        arm_supported=a.arm_supported,
        arm_across_or_out=m.across_or_out,
        wrist_deviated=m.deviated,
        wrist_twist_at_end=m.twist_at_end,
        neck_deg=a.neck_deg,
        neck_twisted=a.neck_twisted,
        trunk_deg=m.trunk,
        trunk_twisted=m.trunk_twisted,
        trunk_side_bent=m.trunk_side_bent,
        legs_supported=a.legs_supported,
        static_or_repeated=a.static or a.repeated,
        load_kg=held,
        load_static_or_repeated=a.static or a.repeated,
        shock=a.shock,
    )
    reba_in = reba.RebaInputs(
        upper_arm_deg=m.upper_arm,
        lower_arm_deg=m.lower_arm,
        wrist_deg=m.wrist,
        trunk_deg=m.trunk,
        trunk_twisted_or_side_bent=m.trunk_twisted or m.trunk_side_bent,
        neck_deg=a.neck_deg,
        neck_twisted_or_side_bent=a.neck_twisted,
        bilateral_weight_bearing=a.legs_supported,
        knee_deg=m.knee,
        seated=m.seated,
        load_kg=total,
        shock=a.shock,
        arm_abducted_or_rotated=m.abducted or m.rotated,
        shoulder_raised=a.shoulder_raised,
        arm_supported=a.arm_supported,
        wrist_deviated_or_twisted=m.deviated or m.twist_at_end,
        coupling=a.coupling,
        static=a.static,
        repeated=a.repeated,
        rapid_changes=a.rapid_changes,
    )
    return SideScores(side, rula_in, rula.score(rula_in), reba_in, reba.score(reba_in), assumed)


def _sagittal(body: BodyModel, q: np.ndarray) -> _Measured:
    i = body.index
    return _Measured(math.degrees(q[i["shoulder_flexion"]]), math.degrees(q[i["elbow_flexion"]]))


def _frontal(q: np.ndarray) -> _Measured:
    return _Measured(90.0, math.degrees(q[0]), abducted=True)


def _human(body: BodyModel, q: np.ndarray, side: str) -> _Measured:
    i, deg = body.index, {d: math.degrees(q[k]) for d, k in body.index.items()}
    trunk, upper_arm, wrist_y, shoulder_y = _compiled(body, side)(q=q)["out"].tolist()
    twist = float(parameters.value("plausibility", "trunk_twist"))
    neutral, abducted = value("neutral_tolerance"), value("arm_abducted")
    pronation = f"forearm_pronation_{side}"
    lower, upper = body.lower[i[pronation]], body.upper[i[pronation]]
    near = float(parameters.value("plausibility", "near_limit")) * (upper - lower)
    outward = -1.0 if side == "r" else 1.0
    knees = [deg[k] for k in ("knee_flexion_r", "knee_flexion_l") if k in deg]
    return _Measured(
        upper_arm=upper_arm,
        lower_arm=deg[f"elbow_flexion_{side}"],
        wrist=deg[f"wrist_flexion_{side}"],
        trunk=trunk,
        knee=max(knees, default=0.0),
        abducted=deg[f"shoulder_abduction_{side}"] > abducted,
        rotated=abs(deg[f"shoulder_rotation_{side}"]) > abducted,
        across_or_out=wrist_y * outward < 0.0
        or (wrist_y - shoulder_y) * outward > value("out_to_side"),
        deviated=abs(deg[f"wrist_deviation_{side}"]) > neutral,
        twist_at_end=bool(min(q[i[pronation]] - lower, upper - q[i[pronation]]) <= near),
        trunk_twisted=abs(deg["lumbar_rotation"]) > twist,
        trunk_side_bent=abs(deg["lumbar_bending"]) > twist,
        seated=not knees,
    )


#: Per thread, the compiled geometry of the bodies scored last (``Compiled`` buffers are
#: one thread's).
_threads = threading.local()
KEPT_GEOMETRIES = 32


def _compiled(body: BodyModel, side: str) -> Compiled:
    """``_geometry`` evaluated in buffers of this thread's (25 µs a call less than a
    CasADi call, a seventh of a posture's scoring)."""
    kept: OrderedDict = _threads.__dict__.setdefault("geometry", OrderedDict())
    key = (id(body), side)
    if key not in kept or kept[key][0] is not body:
        kept[key] = (body, Compiled(_geometry(body, side)))
        while len(kept) > KEPT_GEOMETRIES:
            kept.popitem(last=False)
    kept.move_to_end(key)
    return kept[key][1]


@lru_cache(maxsize=32)
def _geometry(body: BodyModel, side: str) -> ca.Function:
    """``f(q)``: trunk flexion from the vertical [deg], the upper arm's signed angle from the
    trunk's downward axis [deg], and the wrist's and the shoulder's sideways positions [m]
    in the trunk's frame (y to the subject's left, origin on the midline)."""
    thorax = body.ancestors(f"shoulder_flexion_{side}")[-2]
    rot = body.rotation(thorax)
    up, left = rot[:, 2], rot[:, 1]
    forward = ca.cross(left, ca.DM([0.0, 0.0, 1.0]))
    trunk = ca.atan2(ca.dot(up, forward), up[2])
    origin = body.point(thorax, body.dofs[body.index[thorax]].origin)
    shoulder, elbow = body.landmark(f"shoulder_{side}"), body.landmark(f"elbow_{side}")
    local = rot.T @ (elbow - shoulder)
    elevation = ca.atan2(ca.norm_2(local[:2]), -local[2])
    behind = ca.logic_and(local[0] < 0, ca.fabs(local[0]) > ca.fabs(local[1]))
    upper_arm = ca.if_else(behind, -elevation, elevation)
    wrist_y = (rot.T @ (body.landmark(f"wrist_{side}") - origin))[1]
    shoulder_y = (rot.T @ (shoulder - origin))[1]
    out = ca.vertcat(trunk * 180 / ca.pi, upper_arm * 180 / ca.pi, wrist_y, shoulder_y)
    return ca.Function("rula_reba_geometry", [body.q], [out], ["q"], ["out"])
