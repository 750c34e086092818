"""The body models the product ships, as instances of the general kinematic tree (docs/model.md).

World frame at the right shoulder joint centre: x forward, y to the subject's
left, z up. Segment lengths, masses and centres of mass come in already
scaled (de Leva 1996); ranges in rad.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Protocol

from casadi_posture.body.tree import BodyModel, Dof, Landmark, Segment, Vector3


class SegmentGeometry(Protocol):
    """What a builder needs of a segment: ``length`` [m], ``mass`` [kg], ``com_distance`` [m]."""

    length: float
    mass: float

    @property
    def com_distance(self) -> float: ...


Builder = Callable[
    [Mapping[str, SegmentGeometry], Mapping[str, tuple[float, float]], float], BodyModel
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
_SAGITTAL_FLEXION_AXIS = (0.0, -1.0, 0.0)
_FRONTAL_FLEXION_AXIS = (-1.0, 0.0, 0.0)


def _along(direction: Vector3, distance: float) -> Vector3:
    return (direction[0] * distance, direction[1] * distance, direction[2] * distance)


def _straight_arm(
    segments: Mapping[str, SegmentGeometry],
    direction: Vector3,
    upper_arm_dof: str | None,
    forearm_dof: str,
) -> tuple[list[Segment], list[Landmark]]:
    """Segments and landmarks of a straight right arm from the shoulder along ``direction``.

    The upper arm and the elbow move with ``upper_arm_dof`` (``None``: fixed);
    the forearm, wrist and hand with ``forearm_dof``.
    """
    ua, fa, hand = segments["upper_arm"], segments["forearm"], segments["hand"]
    elbow, wrist = ua.length, ua.length + fa.length
    body_segments = [
        Segment(
            "upper_arm",
            upper_arm_dof,
            ua.mass,
            _along(direction, ua.com_distance),
            "shoulder",
            "elbow",
        ),
        Segment(
            "forearm",
            forearm_dof,
            fa.mass,
            _along(direction, elbow + fa.com_distance),
            "elbow",
            "wrist",
        ),
        Segment(
            "hand",
            forearm_dof,
            hand.mass,
            _along(direction, wrist + hand.com_distance),
            "wrist",
            "knuckles",
        ),
    ]
    landmarks = [
        Landmark("shoulder", None, (0.0, 0.0, 0.0)),
        Landmark("elbow", upper_arm_dof, _along(direction, elbow)),
        Landmark("wrist", forearm_dof, _along(direction, wrist)),
        Landmark("knuckles", forearm_dof, _along(direction, wrist + hand.length)),
    ]
    return body_segments, landmarks


def sagittal_arm(
    segments: Mapping[str, SegmentGeometry],
    ranges: Mapping[str, tuple[float, float]],
    gravity: float,
) -> BodyModel:
    """The paper's sagittal arm: shoulder flexion and elbow flexion, hand rigid with the forearm.

    Zero posture: arm hanging straight down. Shoulder flexion raises the arm
    forward, elbow flexion bends the forearm forward/up; both axes point to
    the subject's right (-y).
    """
    elbow = _along(_DOWN, segments["upper_arm"].length)
    dofs = [
        Dof(
            "shoulder_flexion",
            None,
            (0.0, 0.0, 0.0),
            _SAGITTAL_FLEXION_AXIS,
            *ranges["shoulder_flexion"],
            "shoulder",
            "shoulder_flexors",
            "shoulder_extensors",
        ),
        Dof(
            "elbow_flexion",
            "shoulder_flexion",
            elbow,
            _SAGITTAL_FLEXION_AXIS,
            *ranges["elbow_flexion"],
            "elbow",
            "elbow_flexors",
            "elbow_extensors",
        ),
    ]
    body_segments, landmarks = _straight_arm(segments, _DOWN, "shoulder_flexion", "elbow_flexion")
    return BodyModel("sagittal_arm", dofs, body_segments, landmarks, gravity=gravity)


def frontal_elbow(
    segments: Mapping[str, SegmentGeometry],
    ranges: Mapping[str, tuple[float, float]],
    gravity: float,
) -> BodyModel:
    """The paper's Fig. 3 case: upper arm fixed, abducted horizontally to the right; only
    the elbow moves, in the frontal plane.

    Zero posture: elbow straight, forearm horizontal pointing right (-y).
    Elbow flexion raises the forearm (axis -x); at 90° it points straight up.
    """
    elbow = _along(_RIGHT, segments["upper_arm"].length)
    dofs = [
        Dof(
            "elbow_flexion",
            None,
            elbow,
            _FRONTAL_FLEXION_AXIS,
            *ranges["elbow_flexion"],
            "elbow",
            "elbow_flexors",
            "elbow_extensors",
        ),
    ]
    body_segments, landmarks = _straight_arm(segments, _RIGHT, None, "elbow_flexion")
    return BodyModel("frontal_elbow", dofs, body_segments, landmarks, gravity=gravity)


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
}
