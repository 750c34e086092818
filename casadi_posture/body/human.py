"""The 3-D human bodies: ``upper_body`` (pelvis fixed) and ``standing`` (on both feet),
written as body trees (docs/model.md, "3-D bodies").

World frame: x forward, y to the subject's left, z up, origin on the floor between the
feet. Zero posture: standing upright, arms hanging at the sides, palms forward. Joint
centres from population sources (``data/joint_centres.toml``), segment masses and centres of
mass from de Leva (1996). Every joint of several DOFs is a chain of revolute DOFs in the
order flexion, abduction (bending, deviation), rotation; signs:

- lumbar: flexion forward, bending to the right, rotation to the left;
- shoulder: flexion forward, abduction sideways, rotation internal; elbow flexion; forearm
  pronation; wrist flexion (palmar), deviation radial;
- hip: flexion, abduction, rotation internal; knee flexion (0 = straight); ankle flexion
  dorsal, inversion.

The standing tree is rooted at the right foot, fixed to the world; its DOFs run up the
right leg to the pelvis (each axis reversed, so every angle keeps its anatomical sign),
then to the trunk, the arms and down the left leg, whose foot a task keeps on the floor.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

from casadi_posture.body.anthropometry import SegmentGeometry, SegmentInertia, resized
from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter
from casadi_posture.spec.schema import (
    BodySpec,
    TreeDofSpec,
    TreeFootSpec,
    TreeHalfJointSpec,
    TreeLandmarkSpec,
    TreeSegmentSpec,
    TreeSpec,
)

Point = tuple[float, float, float]

#: The de Leva segments the 3-D bodies use.
SEGMENTS = (
    "head_neck",
    "upper_trunk",
    "middle_trunk",
    "lower_trunk",
    "upper_arm",
    "forearm",
    "hand",
    "thigh",
    "shank",
    "foot",
)

# DOF: axis of the right side at the zero posture, region, positive and negative groups.
# The left side mirrors the axes that are not about y.
_LUMBAR = (
    ("lumbar_flexion", (0.0, 1.0, 0.0), "trunk", ("lumbar_flexors", "lumbar_extensors")),
    (
        "lumbar_bending",
        (1.0, 0.0, 0.0),
        "trunk",
        ("lumbar_right_benders", "lumbar_left_benders"),
    ),
    (
        "lumbar_rotation",
        (0.0, 0.0, 1.0),
        "trunk",
        ("lumbar_left_rotators", "lumbar_right_rotators"),
    ),
)
_ARM = (
    ("shoulder_flexion", (0.0, -1.0, 0.0), "shoulder", ("shoulder_flexors", "shoulder_extensors")),
    (
        "shoulder_abduction",
        (-1.0, 0.0, 0.0),
        "shoulder",
        ("shoulder_abductors", "shoulder_adductors"),
    ),
    (
        "shoulder_rotation",
        (0.0, 0.0, 1.0),
        "shoulder",
        ("shoulder_internal_rotators", "shoulder_external_rotators"),
    ),
    ("elbow_flexion", (0.0, -1.0, 0.0), "elbow", ("elbow_flexors", "elbow_extensors")),
    ("forearm_pronation", (0.0, 0.0, 1.0), "elbow", ("forearm_pronators", "forearm_supinators")),
    ("wrist_flexion", (0.0, -1.0, 0.0), "hand", ("wrist_flexors", "wrist_extensors")),
    (
        "wrist_deviation",
        (-1.0, 0.0, 0.0),
        "hand",
        ("wrist_radial_deviators", "wrist_ulnar_deviators"),
    ),
)
_LEG = (
    ("hip_flexion", (0.0, -1.0, 0.0), "hip", ("hip_flexors", "hip_extensors")),
    ("hip_abduction", (-1.0, 0.0, 0.0), "hip", ("hip_abductors", "hip_adductors")),
    ("hip_rotation", (0.0, 0.0, 1.0), "hip", ("hip_internal_rotators", "hip_external_rotators")),
    ("knee_flexion", (0.0, 1.0, 0.0), "knee", ("knee_flexors", "knee_extensors")),
    ("ankle_flexion", (0.0, -1.0, 0.0), "ankle", ("ankle_dorsiflexors", "ankle_plantarflexors")),
    ("ankle_inversion", (1.0, 0.0, 0.0), "ankle", ("ankle_invertors", "ankle_evertors")),
)
SIDES = ("r", "l")


def dof_names(model: str) -> tuple[str, ...]:
    """The DOFs of ``upper_body`` or ``standing``, in tree order."""
    arms = [f"{d[0]}_{s}" for s in SIDES for d in _ARM]
    lumbar = [d[0] for d in _LUMBAR]
    if model == "upper_body":
        return (*lumbar, *arms)
    right_leg = [f"{d[0]}_r" for d in reversed(_LEG)]
    left_leg = [f"{d[0]}_l" for d in _LEG]
    return (*right_leg, *lumbar, *arms, *left_leg)


def _mirror(axis: Point, side: str) -> list[float]:
    """The axis of ``side``: the left side negates the components other than y."""
    if side == "r":
        return list(axis)
    return [-axis[0], axis[1], -axis[2]]


@dataclass(frozen=True)
class Skeleton:
    """Joint centres and feet of a body at the zero posture [m] (see module docstring)."""

    ankle_height: float
    knee_height: float
    hip_height: float
    hip_half_width: float
    l5s1: Point
    c7_height: float
    shoulder_height: float
    shoulder_half_width: float
    vertex_height: float
    eyes: Point
    heel_x: float
    ball_x: float
    toe_x: float
    heel_half_width: float
    ball_half_width: float
    toe_half_width: float


def _source(name: str) -> Parameter:
    return parameters.load("joint_centres")[f"joint_centres.{name}"]


def _derived(name: str, value: float, derivation: str, *sources: Parameter) -> Parameter:
    """The record of ``name`` [m] derived from ``sources`` (verified only if all of them are)."""
    status = "verified" if all(s.status == "verified" for s in sources) else "estimate"
    return Parameter(
        name,
        round(value, 6),
        "m",
        f"{derivation} ({'; '.join(dict.fromkeys(s.source for s in sources))})",
        status,
        "+".join(dict.fromkeys(s.evidence for s in sources if s.evidence)) + "+X",
    )


# The limbs' joint centres standing, arms hanging straight: the ANSUR II landmark each lies
# at (its height above the floor as a sum of signed measurements), the landmark's name, and
# the record of the centre's offset below it.
_CENTRES = {
    "knee": (
        (("knee_height_mid_patella", 1.0),),
        "knee height, mid-patella",
        "knee_below_mid_patella",
    ),
    "hip": ((("trochanterion_height", 1.0),), "trochanterion height", "hip_below_trochanterion"),
    "elbow": (
        (("acromial_height", 1.0), ("acromion_radiale_length", -1.0)),
        "radiale height (acromial height − acromion–radiale length)",
        "elbow_below_radiale",
    ),
    "wrist": (
        (
            ("acromial_height", 1.0),
            ("acromion_radiale_length", -1.0),
            ("radiale_stylion_length", -1.0),
        ),
        "stylion height, arm hanging straight (acromial height − acromion–radiale length"
        " − radiale–stylion length)",
        "wrist_below_stylion",
    ),
}

# The limb segments whose length is the distance between two centres: segment, upper centre,
# lower centre, and which of them is placed first (the other follows from the length).
_SPANS = (
    ("shank", "knee", "ankle", "ankle"),
    ("thigh", "hip", "knee", "knee"),
    ("upper_arm", "shoulder", "elbow", "shoulder"),
    ("forearm", "elbow", "wrist", "elbow"),
)


def _given_length(geometry: SegmentGeometry) -> bool:
    """Whether ``geometry``'s length is the problem file's (or carries no record)."""
    if not isinstance(geometry, SegmentInertia):
        return True
    return any(p.status == "user" for p in geometry.parameters if p.name.endswith(".length"))


def skeleton(
    body: BodySpec, segments: Mapping[str, SegmentGeometry], hip_height: float | None = None
) -> tuple[Skeleton, dict[str, SegmentGeometry], list[Parameter]]:
    """The joint centres of ``body`` (sex, stature), its segments with the shank, thigh,
    upper arm and forearm as long as the distances between the limbs' joint centres, and the
    records of their derivation.

    Standing, arms hanging, the ankle, knee, hip, elbow and wrist centres lie at ANSUR II
    landmarks scaled by stature (``_CENTRES``), the shoulder's below the acromion (Rab 2002),
    unless the problem file gives a limb segment's length; then the leg's centres above and
    the arm's below follow from it. ``hip_height`` [m] moves the hips (and all above) to that
    height above the floor (a seated ``upper_body``)."""
    sex, stature = body.sex, body.stature_m
    records: list[Parameter] = []
    source = _source

    def ansur(name: str) -> float:
        scale = stature / source(f"ansur_2.{sex}.stature").value
        return source(f"ansur_2.{sex}.{name}").value * scale

    def record(name: str, value: float, derivation: str, *sources: Parameter) -> float:
        records.append(_derived(f"body.{name}", value, derivation, *sources))
        return value

    ansur_ref = source(f"ansur_2.{sex}.stature")
    per = f"× stature {stature:g} m / {ansur_ref.value:g} m"
    reed = f"reed_1999.{sex}"
    pw = source(f"{reed}.pelvis_width").value * stature / source(f"{reed}.stature").value
    reed_source = source(f"{reed}.pelvis_width")
    rab = source("rab_2002.gh_below_acromion")
    biacromial = ansur("biacromial_breadth")
    heights = {
        "ankle": ansur("lateral_malleolus_height"),
        "shoulder": ansur("acromial_height") - rab.value * biacromial,
    }
    derived = {
        "ankle": _derived(
            "body.ankle_height",
            heights["ankle"],
            f"ANSUR II mean lateral malleolus height {per}",
            source(f"ansur_2.{sex}.lateral_malleolus_height"),
        ),
        "shoulder": _derived(
            "body.shoulder_height",
            heights["shoulder"],
            f"ANSUR II mean acromial height − Rab 2002 {rab.value:g} × biacromial breadth, {per}",
            source(f"ansur_2.{sex}.acromial_height"),
            rab,
        ),
    }

    def centre(joint: str) -> None:
        """``joint``'s centre at its ANSUR II landmark (``_CENTRES``)."""
        terms, label, offset = _CENTRES[joint]
        measured = [source(f"ansur_2.{sex}.{name}") for name, _ in terms]
        below = source(f"landmark_centres.{offset}")
        landmark = sum(sign * ansur(name) for name, sign in terms)
        heights[joint] = landmark - below.value
        means = ", ".join(f"{m.value:g} m" for m in measured)
        derived[joint] = _derived(
            f"body.{joint}_height",
            heights[joint],
            f"ANSUR II mean {label} ({means}) {per}, the {joint} centre {below.value:g} m below it",
            *measured,
            below,
        )

    limbs = dict(segments)
    for name, upper, lower, first in _SPANS:
        then = lower if first == upper else upper
        geometry = segments[name]
        if _given_length(geometry):
            sign = -1.0 if then == lower else 1.0
            heights[then] = heights[first] + sign * geometry.length
            derived[then] = _derived(
                f"body.{then}_height",
                heights[then],
                f"{first} height {'−' if sign < 0 else '+'} the given {name} length"
                f" {geometry.length:g} m",
                derived[first],
            )
            continue
        centre(then)
        limbs[name] = resized(
            geometry,
            Parameter(
                f"segment.{name}.length",
                heights[upper] - heights[lower],
                "m",
                f"{upper} centre height − {lower} centre height standing"
                f" (body.{upper}_height − body.{lower}_height)",
                "estimate",
                derived[then].evidence,
            ),
        )
        records += limbs[name].parameters
    records += [derived[joint] for joint in ("ankle", "knee", "elbow", "wrist")]
    standing_hip = heights["hip"]
    hip = standing_hip if hip_height is None else hip_height
    lift = hip - standing_hip
    if hip_height is None:
        records.append(derived["hip"])
    else:
        records.append(
            Parameter("body.hip_height", hip, "m", "the file's body.hip_height_m", "user")
        )
    hip_half = record(
        "hip_half_width",
        source(f"{reed}.hip_lateral").value * pw,
        f"Reed 1999 {source(f'{reed}.hip_lateral').value:g} × pelvis width {pw:.4g} m",
        reed_source,
    )
    up = (source(f"{reed}.l5s1_up").value + source(f"{reed}.hip_down").value) * pw
    back = (source(f"{reed}.l5s1_back").value - source(f"{reed}.hip_back").value) * pw
    record(
        "l5s1_height", hip + up, "hip height + Reed 1999 L5/S1 above the hip centres", reed_source
    )
    record("l5s1_x", -back, "Reed 1999 L5/S1 behind the hip centres", reed_source)
    c7 = record(
        "c7_height",
        ansur("cervicale_height") + lift,
        f"ANSUR II mean cervicale height {per}",
        source(f"ansur_2.{sex}.cervicale_height"),
    )
    shoulder = heights["shoulder"] + lift
    records.append(replace(derived["shoulder"], value=round(shoulder, 6)))
    shoulder_half = record(
        "shoulder_half_width",
        biacromial / 2,
        f"ANSUR II mean biacromial breadth / 2 {per}",
        source(f"ansur_2.{sex}.biacromial_breadth"),
    )
    head = segments["head_neck"].length
    estimate = "estimates"
    vertex = c7 + head
    eyes = (
        source(f"{estimate}.eyes_forward").value * head,
        0.0,
        vertex - source(f"{estimate}.eyes_below_vertex").value * head,
    )
    foot_length = ansur("foot_length")
    heel_x = -source(f"{estimate}.heel_behind_ankle").value * foot_length
    foot_breadth = ansur("foot_breadth")
    for name in ("foot_length", "foot_breadth", "heel_breadth", "ball_of_foot_length"):
        record(
            name,
            ansur(name),
            f"ANSUR II mean {name.replace('_', ' ')} {per}",
            source(f"ansur_2.{sex}.{name}"),
        )
    record(
        "heel_x",
        heel_x,
        "heel behind the ankle centre by a fraction of the foot length",
        source(f"{estimate}.heel_behind_ankle"),
    )
    return (
        Skeleton(
            ankle_height=heights["ankle"],
            knee_height=heights["knee"] + lift,
            hip_height=hip,
            hip_half_width=hip_half,
            l5s1=(-back, 0.0, hip + up),
            c7_height=c7,
            shoulder_height=shoulder,
            shoulder_half_width=shoulder_half,
            vertex_height=vertex,
            eyes=eyes,
            heel_x=heel_x,
            ball_x=heel_x + ansur("ball_of_foot_length"),
            toe_x=heel_x + foot_length,
            heel_half_width=ansur("heel_breadth") / 2,
            ball_half_width=foot_breadth / 2,
            toe_half_width=source(f"{estimate}.toe_width").value * foot_breadth / 2,
        ),
        limbs,
        records,
    )


class _Tree:
    """Collects a tree's DOFs, segments, landmarks and feet."""

    def __init__(self, ranges: Mapping[str, tuple[float, float]]) -> None:
        self.ranges = ranges
        self.dofs: list[TreeDofSpec] = []
        self.segments: list[TreeSegmentSpec] = []
        self.landmarks: list[TreeLandmarkSpec] = []
        self.feet: list[TreeFootSpec] = []

    def dof(
        self,
        entry: tuple[str, Point, str, tuple[str, str]],
        side: str | None,
        parent: str | None,
        origin: Point,
        reverse: bool = False,
    ) -> str:
        """Add a DOF of ``_LUMBAR``/``_ARM``/``_LEG`` on ``side`` (None: the midline); a
        ``reverse`` DOF carries its parent segment instead of its child (axis negated)."""
        kind, axis, region, (positive, negative) = entry
        suffix = "" if side is None else f"_{side}"
        name = kind + suffix
        direction = list(axis) if side is None else _mirror(axis, side)
        if reverse:
            direction = [-c for c in direction]
        self.dofs.append(
            TreeDofSpec(
                name=name,
                parent=parent,
                origin_m=list(origin),
                axis=direction,
                range_deg=list(self.ranges[name]),
                positive=TreeHalfJointSpec(name=positive + suffix, region=region),
                negative=TreeHalfJointSpec(name=negative + suffix, region=region),
            )
        )
        return name

    def segment(
        self,
        name: str,
        dof: str | None,
        mass: float,
        com: Point,
        ends: tuple[str, str] | None = None,
    ) -> None:
        proximal, distal = ends if ends is not None else (None, None)
        self.segments.append(
            TreeSegmentSpec(
                name=name, dof=dof, mass_kg=mass, com_m=list(com), proximal=proximal, distal=distal
            )
        )

    def landmark(self, name: str, dof: str | None, position: Point) -> None:
        self.landmarks.append(TreeLandmarkSpec(name=name, dof=dof, position_m=list(position)))

    def tree(self, name: str) -> TreeSpec:
        return TreeSpec(
            name=name,
            dofs=self.dofs,
            segments=self.segments,
            landmarks=self.landmarks,
            feet=self.feet,
        )


def _below(top: Point, distance: float) -> Point:
    return (top[0], top[1], top[2] - distance)


def _trunk(
    t: _Tree, sk: Skeleton, segments: Mapping[str, SegmentGeometry], pelvis: str | None
) -> str:
    """The pelvis (carried by ``pelvis``), lumbar joint, trunk and head; the thorax's DOF."""
    mid_hip = (0.0, 0.0, sk.hip_height)
    c7 = (0.0, 0.0, sk.c7_height)
    t.landmark("mid_hip", pelvis, mid_hip)
    t.landmark("l5s1", pelvis, sk.l5s1)
    t.landmark("hip_r", pelvis, (0.0, -sk.hip_half_width, sk.hip_height))
    t.landmark("hip_l", pelvis, (0.0, sk.hip_half_width, sk.hip_height))
    parent = pelvis
    for entry in _LUMBAR:
        parent = t.dof(entry, None, parent, sk.l5s1)
    thorax = parent
    t.landmark("c7", thorax, c7)
    t.landmark("vertex", thorax, (0.0, 0.0, sk.vertex_height))
    t.landmark("eyes", thorax, sk.eyes)
    # de Leva's trunk parts from C7 down, scaled to the distance from C7 to the hips.
    parts = ("upper_trunk", "middle_trunk", "lower_trunk")
    scale = (sk.c7_height - sk.hip_height) / sum(segments[p].length for p in parts)
    top = c7[2]
    for part in parts:
        geometry = segments[part]
        com = (0.0, 0.0, top - scale * geometry.com_distance)
        carrier = pelvis if part == "lower_trunk" else thorax
        t.segment(part, carrier, geometry.mass, com)
        top -= scale * geometry.length
    head = segments["head_neck"]
    t.segment(
        "head_neck",
        thorax,
        head.mass,
        (0.0, 0.0, sk.vertex_height - head.com_distance),
        ("c7", "vertex"),
    )
    t.segment("pelvis", pelvis, 0.0, mid_hip, ("hip_r", "hip_l"))
    t.segment("lumbar_spine", pelvis, 0.0, sk.l5s1, ("mid_hip", "l5s1"))
    t.segment("spine", thorax, 0.0, c7, ("l5s1", "c7"))
    return thorax


def _arm(
    t: _Tree, sk: Skeleton, segments: Mapping[str, SegmentGeometry], side: str, thorax: str
) -> None:
    y = sk.shoulder_half_width * (-1.0 if side == "r" else 1.0)
    shoulder = (0.0, y, sk.shoulder_height)
    ua, fa, hand = segments["upper_arm"], segments["forearm"], segments["hand"]
    elbow = _below(shoulder, ua.length)
    wrist = _below(elbow, fa.length)
    knuckles = _below(wrist, hand.length)
    t.landmark(f"shoulder_{side}", thorax, shoulder)
    t.segment(f"shoulder_girdle_{side}", thorax, 0.0, shoulder, ("c7", f"shoulder_{side}"))
    parent = thorax
    names = []
    for entry, origin in zip(_ARM, (shoulder,) * 3 + (elbow, elbow, wrist, wrist), strict=True):
        parent = t.dof(entry, side, parent, origin)
        names.append(parent)
    upper_arm_dof, forearm_dof, hand_dof = names[2], names[4], names[6]
    t.landmark(f"elbow_{side}", upper_arm_dof, elbow)
    t.landmark(f"wrist_{side}", forearm_dof, wrist)
    t.landmark(f"grip_{side}", hand_dof, _below(wrist, hand.com_distance))
    t.landmark(f"knuckles_{side}", hand_dof, knuckles)
    parts = (
        ("upper_arm", upper_arm_dof, ua, shoulder, "shoulder", "elbow"),
        ("forearm", forearm_dof, fa, elbow, "elbow", "wrist"),
        ("hand", hand_dof, hand, wrist, "wrist", "knuckles"),
    )
    for name, dof, geometry, top, proximal, distal in parts:
        _hanging(t, side, name, dof, geometry, top, (proximal, distal))


def _hanging(
    t: _Tree,
    side: str,
    name: str,
    dof: str | None,
    geometry: SegmentGeometry,
    top: Point,
    ends: tuple[str, str],
) -> None:
    """A limb segment of ``side`` hanging straight down from ``top`` at the zero posture,
    between the landmarks ``ends`` (side suffix added)."""
    com = _below(top, geometry.com_distance)
    landmarks = (f"{ends[0]}_{side}", f"{ends[1]}_{side}")
    t.segment(f"{name}_{side}", dof, geometry.mass, com, landmarks)


def _leg_points(sk: Skeleton, side: str) -> dict[str, Point]:
    y = sk.hip_half_width * (-1.0 if side == "r" else 1.0)
    return {
        "hip": (0.0, y, sk.hip_height),
        "knee": (0.0, y, sk.knee_height),
        "ankle": (0.0, y, sk.ankle_height),
        "heel": (sk.heel_x, y, 0.0),
        "toe": (sk.toe_x, y, 0.0),
    }


def _sole(sk: Skeleton, y: float) -> list[list[float]]:
    """The outline of a sole centred on ``y``: heel, ball of the foot and toes [m]."""
    return [
        [sk.heel_x, y - sk.heel_half_width, 0.0],
        [sk.ball_x, y - sk.ball_half_width, 0.0],
        [sk.toe_x, y - sk.toe_half_width, 0.0],
        [sk.toe_x, y + sk.toe_half_width, 0.0],
        [sk.ball_x, y + sk.ball_half_width, 0.0],
        [sk.heel_x, y + sk.heel_half_width, 0.0],
    ]


def _leg_segments(
    t: _Tree,
    sk: Skeleton,
    segments: Mapping[str, SegmentGeometry],
    side: str,
    carriers: Mapping[str, str | None],
) -> None:
    """The thigh, shank and foot of ``side``, carried by the DOFs in ``carriers``."""
    p = _leg_points(sk, side)
    thigh, shank, foot = segments["thigh"], segments["shank"], segments["foot"]
    for name in ("knee", "ankle", "heel", "toe"):
        t.landmark(f"{name}_{side}", carriers[name], p[name])
    _hanging(t, side, "thigh", carriers["thigh"], thigh, p["hip"], ("hip", "knee"))
    _hanging(t, side, "shank", carriers["shank"], shank, p["knee"], ("knee", "ankle"))
    foot_com = (sk.heel_x + foot.com_distance, p["ankle"][1], sk.ankle_height / 2)
    t.segment(
        f"foot_{side}", carriers["foot"], foot.mass, foot_com, (f"heel_{side}", f"toe_{side}")
    )
    t.feet.append(
        TreeFootSpec(name=f"foot_{side}", dof=carriers["foot"], outline_m=_sole(sk, p["ankle"][1]))
    )


def upper_body(
    segments: Mapping[str, SegmentGeometry],
    ranges: Mapping[str, tuple[float, float]],
    body: BodySpec,
) -> tuple[TreeSpec, list[Parameter]]:
    """The body above the hips, pelvis fixed to the world (seated, or standing with the
    pelvis held): lumbar 3 DOF, two arms of 7."""
    sk, segments, records = skeleton(body, segments, body.hip_height_m)
    t = _Tree(ranges)
    thorax = _trunk(t, sk, segments, None)
    for side in SIDES:
        _arm(t, sk, segments, side, thorax)
    return t.tree("upper_body"), records


def standing(
    segments: Mapping[str, SegmentGeometry],
    ranges: Mapping[str, tuple[float, float]],
    body: BodySpec,
) -> tuple[TreeSpec, list[Parameter]]:
    """The whole body standing: the upper body on two legs (hip 3, knee, ankle 2 per side),
    the right foot fixed to the world, the left one kept on the floor by a task."""
    sk, segments, records = skeleton(body, segments)
    t = _Tree(ranges)
    right = _leg_points(sk, "r")
    origins = {"hip": right["hip"], "knee": right["knee"], "ankle": right["ankle"]}
    parent = None
    carriers: dict[str, str | None] = {"foot": None, "heel": None, "toe": None, "ankle": None}
    for entry in reversed(_LEG):
        parent = t.dof(entry, "r", parent, origins[entry[0].split("_")[0]], reverse=True)
        if entry[0] == "ankle_flexion":
            carriers["shank"] = carriers["knee"] = parent
        if entry[0] == "knee_flexion":
            carriers["thigh"] = parent
    pelvis = parent
    thorax = _trunk(t, sk, segments, pelvis)
    for side in SIDES:
        _arm(t, sk, segments, side, thorax)
    _leg_segments(t, sk, segments, "r", carriers)
    left = _leg_points(sk, "l")
    parent = pelvis
    carriers = {}
    for entry in _LEG:
        parent = t.dof(entry, "l", parent, left[entry[0].split("_")[0]])
        if entry[0] == "hip_rotation":
            carriers["thigh"] = carriers["knee"] = parent
        if entry[0] == "knee_flexion":
            carriers["shank"] = carriers["ankle"] = parent
    carriers["foot"] = carriers["heel"] = carriers["toe"] = parent
    _leg_segments(t, sk, segments, "l", carriers)
    return t.tree("standing"), records
