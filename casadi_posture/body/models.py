"""The body models the product ships, as instances of the general kinematic tree (docs/model.md).

World frame at the right shoulder joint centre: x forward, y to the subject's
left, z up. Segment lengths, masses and centres of mass come in already
scaled (de Leva 1996); ranges in degrees. Each model is written as the tree a problem
file can hold (`body.tree`), so nothing downstream knows a model by name.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

from casadi_posture.body import human
from casadi_posture.body.anthropometry import SegmentGeometry
from casadi_posture.body.tree import Vector3
from casadi_posture.data.parameters import Parameter
from casadi_posture.spec.schema import (
    BodySpec,
    TreeDofSpec,
    TreeHalfJointSpec,
    TreeLandmarkSpec,
    TreeSegmentSpec,
    TreeSpec,
)

#: A model's tree from its scaled segments, its DOF ranges [deg] and the file's body (sex,
#: stature and mass, for the models whose joint centres depend on them), with the records of
#: the numbers it derived.
Builder = Callable[
    [Mapping[str, SegmentGeometry], Mapping[str, tuple[float, float]], BodySpec],
    tuple[TreeSpec, list[Parameter]],
]


@dataclass(frozen=True)
class ModelRecipe:
    """A named model: the de Leva segments and joint kinds it uses, and its geometry."""

    name: str
    description: str
    segments: tuple[str, ...]
    dofs: tuple[str, ...]
    build: Builder


_DOWN = (0.0, 0.0, -1.0)
_RIGHT = (0.0, -1.0, 0.0)
_SAGITTAL_FLEXION_AXIS = [0.0, -1.0, 0.0]
_FRONTAL_FLEXION_AXIS = [-1.0, 0.0, 0.0]


def _along(direction: Vector3, distance: float) -> list[float]:
    return [direction[0] * distance, direction[1] * distance, direction[2] * distance]


def _dof(
    name: str,
    parent: str | None,
    origin: list[float],
    axis: list[float],
    range_deg: tuple[float, float],
    region: str,
    groups: tuple[str, str],
) -> TreeDofSpec:
    """A DOF whose two muscle groups take the shipped strength of their names."""
    return TreeDofSpec(
        name=name,
        parent=parent,
        origin_m=origin,
        axis=axis,
        range_deg=list(range_deg),
        positive=TreeHalfJointSpec(name=groups[0], region=region),
        negative=TreeHalfJointSpec(name=groups[1], region=region),
    )


def _straight_arm(
    segments: Mapping[str, SegmentGeometry],
    direction: Vector3,
    upper_arm_dof: str | None,
    forearm_dof: str,
) -> tuple[list[TreeSegmentSpec], list[TreeLandmarkSpec]]:
    """Segments and landmarks of a straight right arm from the shoulder along ``direction``.

    The upper arm and the elbow move with ``upper_arm_dof`` (``None``: fixed);
    the forearm, wrist and hand with ``forearm_dof``.
    """
    ua, fa, hand = segments["upper_arm"], segments["forearm"], segments["hand"]
    elbow, wrist = ua.length, ua.length + fa.length
    parts = [
        ("upper_arm", upper_arm_dof, ua, 0.0, "shoulder", "elbow"),
        ("forearm", forearm_dof, fa, elbow, "elbow", "wrist"),
        ("hand", forearm_dof, hand, wrist, "wrist", "knuckles"),
    ]
    body_segments = [
        TreeSegmentSpec(
            name=name,
            dof=dof,
            mass_kg=geometry.mass,
            com_m=_along(direction, start + geometry.com_distance),
            proximal=proximal,
            distal=distal,
        )
        for name, dof, geometry, start, proximal, distal in parts
    ]
    landmarks = [
        TreeLandmarkSpec(name="shoulder", position_m=[0.0, 0.0, 0.0]),
        TreeLandmarkSpec(name="elbow", dof=upper_arm_dof, position_m=_along(direction, elbow)),
        TreeLandmarkSpec(name="wrist", dof=forearm_dof, position_m=_along(direction, wrist)),
        TreeLandmarkSpec(
            name="knuckles", dof=forearm_dof, position_m=_along(direction, wrist + hand.length)
        ),
    ]
    return body_segments, landmarks


def sagittal_arm(
    segments: Mapping[str, SegmentGeometry],
    ranges: Mapping[str, tuple[float, float]],
    body: BodySpec | None = None,
) -> tuple[TreeSpec, list[Parameter]]:
    """The paper's sagittal arm: shoulder flexion and elbow flexion, hand rigid with the forearm.

    Zero posture: arm hanging straight down. Shoulder flexion raises the arm
    forward, elbow flexion bends the forearm forward/up; both axes point to
    the subject's right (-y).
    """
    dofs = [
        _dof(
            "shoulder_flexion",
            None,
            [0.0, 0.0, 0.0],
            _SAGITTAL_FLEXION_AXIS,
            ranges["shoulder_flexion"],
            "shoulder",
            ("shoulder_flexors", "shoulder_extensors"),
        ),
        _dof(
            "elbow_flexion",
            "shoulder_flexion",
            _along(_DOWN, segments["upper_arm"].length),
            _SAGITTAL_FLEXION_AXIS,
            ranges["elbow_flexion"],
            "elbow",
            ("elbow_flexors", "elbow_extensors"),
        ),
    ]
    body_segments, landmarks = _straight_arm(segments, _DOWN, "shoulder_flexion", "elbow_flexion")
    return TreeSpec(name="sagittal_arm", dofs=dofs, segments=body_segments, landmarks=landmarks), []


def frontal_elbow(
    segments: Mapping[str, SegmentGeometry],
    ranges: Mapping[str, tuple[float, float]],
    body: BodySpec | None = None,
) -> tuple[TreeSpec, list[Parameter]]:
    """The paper's Fig. 3 case: upper arm fixed, abducted horizontally to the right; only
    the elbow moves, in the frontal plane.

    Zero posture: elbow straight, forearm horizontal pointing right (-y).
    Elbow flexion raises the forearm (axis -x); at 90° it points straight up.
    """
    dofs = [
        _dof(
            "elbow_flexion",
            None,
            _along(_RIGHT, segments["upper_arm"].length),
            _FRONTAL_FLEXION_AXIS,
            ranges["elbow_flexion"],
            "elbow",
            ("elbow_flexors", "elbow_extensors"),
        ),
    ]
    body_segments, landmarks = _straight_arm(segments, _RIGHT, None, "elbow_flexion")
    return TreeSpec(
        name="frontal_elbow", dofs=dofs, segments=body_segments, landmarks=landmarks
    ), []


MODELS: dict[str, ModelRecipe] = {
    "sagittal_arm": ModelRecipe(
        "sagittal_arm",
        "right arm in the sagittal plane: shoulder flexion + elbow flexion (paper §6)",
        ("upper_arm", "forearm", "hand"),
        ("shoulder_flexion", "elbow_flexion"),
        sagittal_arm,
    ),
    "frontal_elbow": ModelRecipe(
        "frontal_elbow",
        "right elbow in the frontal plane, upper arm fixed horizontal (paper Fig. 3)",
        ("upper_arm", "forearm", "hand"),
        ("elbow_flexion",),
        frontal_elbow,
    ),
    "upper_body": ModelRecipe(
        "upper_body",
        "3-D body above the hips, pelvis fixed: lumbar 3 DOF, two arms of 7 (shoulder 3,"
        " elbow, forearm, wrist 2)",
        human.SEGMENTS[:-1],
        human.dof_names("upper_body"),
        human.upper_body,
    ),
    "standing": ModelRecipe(
        "standing",
        "3-D body standing on both feet: the upper body on two legs (hip 3, knee, ankle 2),"
        " the right foot fixed to the floor",
        human.SEGMENTS,
        human.dof_names("standing"),
        human.standing,
    ),
}
