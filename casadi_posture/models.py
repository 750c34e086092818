"""The body models the product ships, as instances of the general kinematic tree (SPEC §1, §8).

World frame at the right shoulder joint centre: x forward, y to the subject's
left, z up. Segment lengths, masses and centres of mass come in already
scaled (de Leva 1996); ranges in rad.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Protocol

from .body import BodyModel, Dof, Landmark, Segment


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


def _along(direction: tuple[float, float, float], distance: float) -> tuple[float, float, float]:
    return (direction[0] * distance, direction[1] * distance, direction[2] * distance)


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
    ua, fa, hand = segments["upper_arm"], segments["forearm"], segments["hand"]
    elbow, wrist = ua.length, ua.length + fa.length
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
            _along(_DOWN, elbow),
            _SAGITTAL_FLEXION_AXIS,
            *ranges["elbow_flexion"],
            "elbow",
            "elbow_flexors",
            "elbow_extensors",
        ),
    ]
    body_segments = [
        Segment(
            "upper_arm",
            "shoulder_flexion",
            ua.mass,
            _along(_DOWN, ua.com_distance),
            "shoulder",
            "elbow",
        ),
        Segment(
            "forearm",
            "elbow_flexion",
            fa.mass,
            _along(_DOWN, elbow + fa.com_distance),
            "elbow",
            "wrist",
        ),
        Segment(
            "hand",
            "elbow_flexion",
            hand.mass,
            _along(_DOWN, wrist + hand.com_distance),
            "wrist",
            "knuckles",
        ),
    ]
    landmarks = [
        Landmark("shoulder", None, (0.0, 0.0, 0.0)),
        Landmark("elbow", "shoulder_flexion", _along(_DOWN, elbow)),
        Landmark("wrist", "elbow_flexion", _along(_DOWN, wrist)),
        Landmark("knuckles", "elbow_flexion", _along(_DOWN, wrist + hand.length)),
    ]
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
    ua, fa, hand = segments["upper_arm"], segments["forearm"], segments["hand"]
    elbow, wrist = ua.length, ua.length + fa.length
    dofs = [
        Dof(
            "elbow_flexion",
            None,
            _along(_RIGHT, elbow),
            _FRONTAL_FLEXION_AXIS,
            *ranges["elbow_flexion"],
            "elbow",
            "elbow_flexors",
            "elbow_extensors",
        ),
    ]
    body_segments = [
        Segment("upper_arm", None, ua.mass, _along(_RIGHT, ua.com_distance), "shoulder", "elbow"),
        Segment(
            "forearm",
            "elbow_flexion",
            fa.mass,
            _along(_RIGHT, elbow + fa.com_distance),
            "elbow",
            "wrist",
        ),
        Segment(
            "hand",
            "elbow_flexion",
            hand.mass,
            _along(_RIGHT, wrist + hand.com_distance),
            "wrist",
            "knuckles",
        ),
    ]
    landmarks = [
        Landmark("shoulder", None, (0.0, 0.0, 0.0)),
        Landmark("elbow", None, _along(_RIGHT, elbow)),
        Landmark("wrist", "elbow_flexion", _along(_RIGHT, wrist)),
        Landmark("knuckles", "elbow_flexion", _along(_RIGHT, wrist + hand.length)),
    ]
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
