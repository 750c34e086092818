"""The problem-file format (TOML), validated with pydantic; docs/problem-files.md documents it.

Key names carry their unit (``_m``, ``_kg``, ``_deg``, ``_s``, ``_Nm``,
``_pct_mvc``); angles in files are degrees. Unknown keys are errors. Every number
must be finite and within the physically meaningful range stated here and in
``docs/problem-files.md``: nan, inf and absurd magnitudes (a position written in
centimetres, a 1e308 kg load) are refused before anything is computed.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    field_validator,
    model_validator,
)

from casadi_posture.spec.overrides import STRENGTH_KEYS

#: The ranges every number of a problem file must lie in (``docs/problem-files.md``).
MAX_POSITION_M = 10.0  # a point farther than this from the origin is a unit slip (cm, mm)
MAX_ANGLE_DEG = 360.0
MAX_LOAD_MASS_KG = 1000.0
MAX_FORCE_N = 10_000.0
MAX_MOMENT_NM = 1_000.0
MAX_PASSIVE_NM = 1_000.0
MAX_PASSIVE_RATE_PER_RAD = 50.0  # with angles within ±360°, exp() stays far from overflow
MIN_STRENGTH_NM, MAX_STRENGTH_NM = 0.1, 2_000.0
#: A strength_scale: a tenth to ten times the shipped default; a strength_ratio: a
#: twentieth to twenty times the body's elbow-flexion strength.
MIN_STRENGTH_SCALE, MAX_STRENGTH_SCALE = 0.1, 10.0
MIN_STRENGTH_RATIO, MAX_STRENGTH_RATIO = 0.05, 20.0
MAX_DURATION_S = 86_400.0
MIN_TIME_STEP_S, MAX_TIME_STEP_S = 0.01, 60.0
MAX_STEPS = 100_000
MAX_SOLVER_ITERATIONS = 100_000
MIN_TOLERANCE, MAX_TOLERANCE = 1e-14, 1e-2
MAX_DIRECTION = 1e6
MAX_COMFORT_WEIGHT = 1e6


def _between(lo: float, hi: float) -> Field:
    return Field(ge=lo, le=hi)


Angle = Annotated[float, _between(-MAX_ANGLE_DEG, MAX_ANGLE_DEG)]
Coordinate = Annotated[float, _between(-MAX_POSITION_M, MAX_POSITION_M)]
Position = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]
Direction = Annotated[
    list[Annotated[float, _between(-MAX_DIRECTION, MAX_DIRECTION)]],
    Field(min_length=3, max_length=3),
]
Force = Annotated[
    list[Annotated[float, _between(-MAX_FORCE_N, MAX_FORCE_N)]], Field(min_length=3, max_length=3)
]
Moment = Annotated[
    list[Annotated[float, _between(-MAX_MOMENT_NM, MAX_MOMENT_NM)]],
    Field(min_length=3, max_length=3),
]
AnglePair = Annotated[list[Angle], Field(min_length=2, max_length=2)]
Angles3 = Annotated[list[Angle], Field(min_length=3, max_length=3)]
PassiveMagnitude = Annotated[float, _between(0.0, MAX_PASSIVE_NM)]
PassiveRate = Annotated[float, _between(0.0, MAX_PASSIVE_RATE_PER_RAD)]
StrengthValue = Annotated[float, _between(MIN_STRENGTH_NM, MAX_STRENGTH_NM)]
#: A factor on a group's shipped default strength (a person weaker or stronger than average).
StrengthScale = Annotated[float, _between(MIN_STRENGTH_SCALE, MAX_STRENGTH_SCALE)]
#: A group's posture-independent strength as a multiple of the body's elbow flexion.
StrengthRatio = Annotated[float, _between(MIN_STRENGTH_RATIO, MAX_STRENGTH_RATIO)]
Priority = Annotated[int, Field(ge=1, le=1000)]
ComfortWeight = Annotated[float, _between(0.0, MAX_COMFORT_WEIGHT)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, allow_inf_nan=False)


def _increasing(pair: list[float]) -> list[float]:
    if not pair[0] < pair[1]:
        raise ValueError("[min, max] with min < max")
    return pair


def _nonzero(vector: list[float]) -> list[float]:
    if sum(c * c for c in vector) < 1e-18:
        raise ValueError("a non-zero vector (length at least 1e-9)")
    return vector


class ExponentialPassiveSpec(Strict):
    """τp = k1·exp(-k2·(q - q1)) - k3·exp(-k4·(q2 - q)); every key required."""

    model: Literal["exponential"] = "exponential"
    k1_Nm: PassiveMagnitude
    k2_per_rad: PassiveRate
    q1_deg: Angle
    k3_Nm: PassiveMagnitude
    k4_per_rad: PassiveRate
    q2_deg: Angle


class LimitTorquePassiveSpec(Strict):
    """The limit-torque convention: ``limit_Nm`` at each anatomical limit (``lower_deg``,
    ``upper_deg``; default: the shipped range of motion, whatever ``range_deg`` says),
    tenfold over each ``decade`` (a fraction of that range) beyond it; unset keys take the
    shipped values."""

    model: Literal["limit_torque"]
    limit_Nm: Annotated[float, Field(gt=0, le=MAX_PASSIVE_NM)] | None = None
    decade: Annotated[float, Field(gt=0.001, le=1.0)] | None = None
    lower_deg: Angle | None = None
    upper_deg: Angle | None = None

    @model_validator(mode="after")
    def _limits(self) -> LimitTorquePassiveSpec:
        if None not in (self.lower_deg, self.upper_deg) and not self.lower_deg < self.upper_deg:
            raise ValueError("lower_deg < upper_deg")
        return self


class GymnastFitPassiveSpec(Strict):
    model: Literal["gymnast_fit"]


class NoPassiveSpec(Strict):
    model: Literal["none"]


class Anderson1999PassiveSpec(Strict):
    """The shipped ligament set of F.C. Anderson's thesis (1999) for a hip, knee or ankle
    DOF, as ``joints.toml`` gives it."""

    model: Literal["anderson_1999"]


def passive_model_tag(value: object) -> str:
    """The passive model's tag; a table without ``model`` is the exponential."""
    if isinstance(value, dict):
        return value.get("model", "exponential")
    return getattr(value, "model", "exponential")


PassiveSpec = Annotated[
    Annotated[ExponentialPassiveSpec, Tag("exponential")]
    | Annotated[LimitTorquePassiveSpec, Tag("limit_torque")]
    | Annotated[GymnastFitPassiveSpec, Tag("gymnast_fit")]
    | Annotated[NoPassiveSpec, Tag("none")]
    | Annotated[Anderson1999PassiveSpec, Tag("anderson_1999")],
    Discriminator(passive_model_tag),
]


class ReshapeSpec(Strict):
    """The paper's reshaping near both limits: within ``width_deg`` of a limit the passive
    torque gains ``step_Nm + slope_Nm_per_rad·depth`` toward the middle of the range."""

    width_deg: Annotated[float, Field(gt=0, le=90)]
    slope_Nm_per_rad: Annotated[float, _between(0.0, MAX_PASSIVE_NM)]
    step_Nm: Annotated[float, _between(0.0, MAX_PASSIVE_NM)] = 0.0


class DofSpec(Strict):
    range_deg: AnglePair | None = None
    passive: PassiveSpec | None = None
    reshape: ReshapeSpec | None = None

    _range = field_validator("range_deg")(lambda v: v if v is None else _increasing(v))


class SegmentSpec(Strict):
    mass_kg: Annotated[float, _between(0.0, 300.0)] | None = None
    length_m: Annotated[float, Field(gt=0, le=2.5)] | None = None
    com_fraction: Annotated[float, Field(ge=0, le=1)] | None = None


class StrengthCurveSpec(Strict):
    dof: str
    angle_deg: list[Angle] = Field(min_length=2, max_length=1000)
    strength_Nm: list[StrengthValue] = Field(min_length=2, max_length=1000)

    @model_validator(mode="after")
    def _table(self) -> StrengthCurveSpec:
        if len(self.angle_deg) != len(self.strength_Nm):
            raise ValueError("angle_deg and strength_Nm of the same length")
        if any(b <= a for a, b in zip(self.angle_deg, self.angle_deg[1:], strict=False)):
            raise ValueError("angle_deg strictly increasing")
        return self


def _one_strength(spec: Any) -> None:
    """At most one of a group's strength keys (``STRENGTH_KEYS``)."""
    given = [k for k in STRENGTH_KEYS if getattr(spec, k) is not None]
    if len(given) > 1:
        raise ValueError(f"one of {', '.join(STRENGTH_KEYS)}, not {' and '.join(given)}")


class HalfJointSpec(Strict):
    strength_Nm: StrengthValue | None = None
    strength_curve: StrengthCurveSpec | None = None
    strength_scale: StrengthScale | None = None
    strength_ratio: StrengthRatio | None = None

    @model_validator(mode="after")
    def _one(self) -> HalfJointSpec:
        _one_strength(self)
        return self


Name = Annotated[str, Field(min_length=1, max_length=100, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")]
#: The most DOFs a tree may have (a whole-body model has about 40).
MAX_TREE_DOFS = 200


class TreeHalfJointSpec(Strict):
    """A muscle group of a DOF: its strength (left out: the shipped default of a group of
    that name) and the joint region whose endurance data it takes (default ``general``)."""

    name: Name
    strength_Nm: StrengthValue | None = None
    strength_curve: StrengthCurveSpec | None = None
    strength_scale: StrengthScale | None = None
    strength_ratio: StrengthRatio | None = None
    region: Name = "general"

    @model_validator(mode="after")
    def _one(self) -> TreeHalfJointSpec:
        _one_strength(self)
        return self


class TreeDofSpec(Strict):
    """A revolute DOF: its joint centre and axis in the world at the zero posture, its
    range, its passive torque (left out: the shipped model of a DOF of that name, else the
    limit-torque convention at this range) and its two muscle groups, ``positive`` driving
    the angle up and ``negative`` down."""

    name: Name
    parent: Name | None = None
    origin_m: Position
    axis: Direction
    range_deg: AnglePair
    passive: PassiveSpec | None = None
    reshape: ReshapeSpec | None = None
    positive: TreeHalfJointSpec
    negative: TreeHalfJointSpec

    _axis = field_validator("axis")(_nonzero)
    _range = field_validator("range_deg")(_increasing)


class TreeSegmentSpec(Strict):
    """A rigid segment carried by ``dof`` (left out: fixed to the world); ``proximal`` and
    ``distal`` name the landmarks a stick figure joins for it."""

    name: Name
    dof: Name | None = None
    mass_kg: Annotated[float, _between(0.0, 300.0)]
    com_m: Position
    proximal: Name | None = None
    distal: Name | None = None


class TreeLandmarkSpec(Strict):
    """A named point carried by ``dof`` (left out: fixed to the world)."""

    name: Name
    dof: Name | None = None
    position_m: Position


class TreeFootSpec(Strict):
    """A foot on the floor: the outline of its sole [m, world, zero posture; z = 0 is the
    floor], carried by ``dof`` (left out: fixed to the world, the tree's root foot)."""

    name: Name
    dof: Name | None = None
    outline_m: list[Position] = Field(min_length=3, max_length=16)


class TreeSpec(Strict):
    """A body described in the file: DOFs in topological order (a parent before its
    children), segments and landmarks, all at the zero posture in the world frame, and the
    feet it stands on (none: a body fixed to the world, e.g. seated)."""

    name: Name = "custom"
    dofs: list[TreeDofSpec] = Field(min_length=1, max_length=MAX_TREE_DOFS)
    segments: list[TreeSegmentSpec] = Field(min_length=1, max_length=4 * MAX_TREE_DOFS)
    landmarks: list[TreeLandmarkSpec] = Field(default=[], max_length=4 * MAX_TREE_DOFS)
    feet: list[TreeFootSpec] = Field(default=[], max_length=2)


class BodySpec(Strict):
    """A built-in ``model`` (with overrides of its DOFs, segments and half-joints) or a
    ``tree`` of the file's own."""

    model: str | None = None
    tree: TreeSpec | None = None
    sex: Literal["male", "female"] = "male"
    stature_m: Annotated[float, _between(0.5, 2.5)] = 1.741
    mass_kg: Annotated[float, _between(10.0, 300.0)] = 73.0
    age_years: Annotated[float, Field(ge=18, le=100)] = 30.0
    hip_height_m: Annotated[float, _between(0.2, 1.5)] | None = None
    dofs: dict[str, DofSpec] = {}
    segments: dict[str, SegmentSpec] = {}
    half_joints: dict[str, HalfJointSpec] = {}

    @model_validator(mode="after")
    def _source(self) -> BodySpec:
        if (self.model is None) == (self.tree is None):
            raise ValueError("exactly one of model (a built-in body) or tree (your own)")
        if self.tree is not None and (self.dofs or self.segments or self.half_joints):
            raise ValueError(
                "dofs, segments and half_joints only with model: change a tree in the tree"
            )
        return self


class LoadSpec(Strict):
    name: str
    at: str
    mass_kg: Annotated[float, _between(0.0, MAX_LOAD_MASS_KG)] = 0.0
    force_N: Force = (0.0, 0.0, 0.0)
    moment_Nm: Moment = (0.0, 0.0, 0.0)


class _Task(Strict):
    name: str
    priority: Priority


class PositionTask(_Task):
    kind: Literal["position"]
    effector: str
    target_m: Position


class LineTask(_Task):
    """Attraction of an effector to a line through ``point_m``, along ``direction`` or
    at ``elevation_deg`` above the forward horizontal, turned by ``azimuth_deg`` about z."""

    kind: Literal["line"]
    effector: str
    point_m: Position
    direction: Direction | None = None
    elevation_deg: Annotated[float, _between(-90.0, 90.0)] | None = None
    azimuth_deg: Angle | None = None

    _direction = field_validator("direction")(lambda v: v if v is None else _nonzero(v))

    @model_validator(mode="after")
    def _one(self) -> LineTask:
        if (self.direction is None) == (self.elevation_deg is None):
            raise ValueError("exactly one of direction or elevation_deg")
        if self.azimuth_deg is not None and self.elevation_deg is None:
            raise ValueError("azimuth_deg only together with elevation_deg")
        return self


class PlaneTask(_Task):
    kind: Literal["plane"]
    effector: str
    point_m: Position
    normal: Direction

    _normal = field_validator("normal")(_nonzero)


class OrientationTask(_Task):
    """Orientation of a segment's frame, as roll-pitch-yaw about the world x, y, z [deg]."""

    kind: Literal["orientation"]
    segment: str
    target_rpy_deg: Angles3


class ComTask(_Task):
    """Whole-body centre of mass (with the held loads' masses unless ``include_loads`` is
    false) over a point, in the listed world axes (balance); left out, the point is where
    it is at the problem's posture."""

    kind: Literal["com"]
    target_m: Position | None = None
    axes: Literal["x", "y", "z", "xy", "xz", "yz", "xyz"] = "xyz"
    include_loads: bool = True


class FeetTask(_Task):
    """Keep every foot the body's DOFs carry where it stands at the zero posture: the
    position and orientation of its sole (standing on both feet)."""

    kind: Literal["feet"]


class GazeTask(_Task):
    """Look at a point: the direction ``forward`` of a segment's frame (at the zero posture,
    world) along the line from the landmark ``eye`` to ``target_m``."""

    kind: Literal["gaze"]
    segment: str
    eye: str
    forward: Direction = [1.0, 0.0, 0.0]
    target_m: Position

    _forward = field_validator("forward")(_nonzero)


class PostureTask(_Task):
    kind: Literal["posture"]
    reference_deg: dict[str, Angle]


class ComfortTask(_Task):
    """How uncomfortable the posture is, minimised at the lowest level to settle what the
    tasks above leave free (docs/comfort.md): a named ``measure``, the weights of its terms,
    and per DOF the joint weights and neutral angles [deg] that replace the shipped ones."""

    kind: Literal["comfort"]
    measure: Literal["joint_displacement", "discomfort", "discomfort_effort"] = "discomfort_effort"
    weights: dict[Literal["displacement", "limits", "effort"], ComfortWeight] = {}
    joint_weights: dict[str, ComfortWeight] = {}
    neutral_deg: dict[str, Angle] = {}


Task = Annotated[
    PositionTask
    | LineTask
    | PlaneTask
    | OrientationTask
    | ComTask
    | FeetTask
    | GazeTask
    | PostureTask
    | ComfortTask,
    Field(discriminator="kind"),
]


class FatigueSpec(Strict):
    endurance: str | None = None
    recovery_law: Literal["threshold", "continuous", "3cc_r"] = "threshold"
    fatigue_threshold: Annotated[float, Field(gt=0, le=1)] = 0.8
    recovery_threshold: Annotated[float, Field(gt=0, le=1)] = 0.5
    strategy: Literal["active", "passive"] = "active"
    r_min: Annotated[float, Field(ge=0, le=1)] = 0.9
    load_threshold_pct_mvc: Annotated[float, Field(ge=0, le=100)] | None = None
    epsilon_Nm: Annotated[float, Field(gt=0, le=100)] = 0.05
    beta: Annotated[float, Field(gt=0, lt=1)] = 0.5
    max_step_deg: Annotated[float, Field(gt=0, le=30)] = 1.0
    alpha_rad_per_Nm2: Annotated[float, Field(ge=-1e-2, lt=0)] = -1e-4
    keep_levels: Annotated[int, Field(ge=0, le=1000)] = 0
    adjustment: Literal["paper", "whole_body"] | None = None
    fatigue_weight: Annotated[float, _between(0.0, 1000.0)] | None = None

    @model_validator(mode="after")
    def _thresholds(self) -> FatigueSpec:
        if not self.recovery_threshold < self.fatigue_threshold:
            raise ValueError(
                "0 < recovery_threshold < fatigue_threshold <= 1, got recovery_threshold = "
                f"{self.recovery_threshold:g} and fatigue_threshold = {self.fatigue_threshold:g}"
            )
        if self.load_threshold_pct_mvc is not None and self.recovery_law == "3cc_r":
            raise ValueError(
                "load_threshold_pct_mvc only with recovery_law = 'threshold' or 'continuous'"
            )
        return self

    @model_validator(mode="before")
    @classmethod
    def _renamed(cls, data: object) -> object:
        if isinstance(data, dict) and "model" in data:
            raise ValueError(
                "recovery_law = 'threshold', 'continuous' or '3cc_r' instead of model "
                "(renamed: holding_time is threshold)"
            )
        return data


class SimulationSpec(Strict):
    duration_s: Annotated[float, Field(gt=0, le=MAX_DURATION_S)] = 600.0
    time_step_s: Annotated[float, _between(MIN_TIME_STEP_S, MAX_TIME_STEP_S)] = 1.0

    @model_validator(mode="after")
    def _step(self) -> SimulationSpec:
        if self.time_step_s > self.duration_s:
            raise ValueError(
                f"time_step_s <= duration_s, got {self.time_step_s:g} s > {self.duration_s:g} s"
            )
        if self.steps > MAX_STEPS:
            raise ValueError(
                f"at most {MAX_STEPS} steps (duration_s / time_step_s), got {self.steps}: "
                "a longer time step or a shorter duration"
            )
        return self

    @property
    def steps(self) -> int:
        """Steps of the run, the start included."""
        return math.floor(self.duration_s / self.time_step_s + 1e-9) + 1


class ScheduleSpec(Strict):
    """A work–rest schedule: hold the tasks for ``t_on_s``, put the load down and rest for
    ``t_off_s``, repeated from the start of the run. Each phase lasts its time rounded up
    to a whole number of ``simulation.time_step_s`` (docs/problem-files.md)."""

    t_on_s: Annotated[float, Field(gt=0, le=MAX_DURATION_S)]
    t_off_s: Annotated[float, _between(0.0, MAX_DURATION_S)]


class ErgonomicsSpec(Strict):
    """What RULA and REBA need that the body and the tasks do not say (docs/rula_reba.md);
    a key left out keeps its documented default and is named as assumed in the outputs."""

    neck_deg: Annotated[float, _between(-90.0, 90.0)] | None = None
    neck_twisted: bool | None = None
    shoulder_raised: bool | None = None
    arm_supported: bool | None = None
    coupling: Literal["good", "fair", "poor", "unacceptable"] | None = None
    legs_supported: bool | None = None
    static: bool | None = None
    repeated: bool | None = None
    rapid_changes: bool | None = None
    shock: bool | None = None

    def given(self) -> dict[str, float | bool | str]:
        """The keys the file set, with their values."""
        return self.model_dump(exclude_none=True)


class BvhSpec(Strict):
    """How a BVH skeleton maps onto the body (docs/motion.md): ``joints`` maps a BVH joint to
    the body's segment it moves; ``up`` and ``forward`` are the file's axes; ``rest_deg`` the
    body's DOF angles [deg] in the skeleton's rest pose (every channel 0); a segment farther
    than ``max_angle_residual_deg`` [deg] from its joint's orientation is flagged."""

    joints: dict[str, str] = {}
    up: Literal["x", "-x", "y", "-y", "z", "-z"] = "y"
    forward: Literal["x", "-x", "y", "-y", "z", "-z"] = "z"
    rest_deg: dict[str, Angle] = {}
    max_angle_residual_deg: Annotated[float, _between(0.1, 90.0)] = 5.0


class MotionSpec(Strict):
    """How a recorded motion maps onto the body (``casadi-posture evaluate``;
    docs/motion.md): ``columns`` maps a joint-angle file's column names to DOFs (a column
    named as a DOF, or as the DOF with ``_deg``, needs none); NaN gaps up to ``max_gap_s``
    [s] are filled by linear interpolation and counted, longer ones filled and flagged;
    ``hold_missing`` holds a DOF the file does not give at the problem's posture_deg.
    ``markers`` maps a landmark of the body to the C3D marker labels whose mean it is (at
    least 3 landmarks); a frame whose landmark lies farther than ``max_marker_residual_m``
    [m] from its markers after the fit is flagged; ``calibrate_s`` ([start, end] [s]) the
    frames in which the subject stands in posture_deg, upright along the file's ``lab_up``
    axis, where each landmark is placed on its segment at its markers; ``fit`` "segments"
    fits each point from its anchor (the fitted joint up its chain) instead of where it is;
    ``clusters`` maps a landmark no marker sits on (a shoulder's centre) to 3 or more markers
    rigid with it, which carry it from where the calibration places it; ``scale_segments``
    names segments (``forearm``) whose length is measured in the calibration window
    between their end landmarks' markers, the body then built with it.
    ``held_s`` gives, per load name, the
    [start, end] windows [s] of the recording's time during which it is held (a load not
    named is held throughout)."""

    columns: dict[str, str] = {}
    max_gap_s: Annotated[float, _between(0.0, 60.0)] = 0.25
    hold_missing: bool = False
    markers: dict[str, Annotated[list[str], Field(min_length=1)]] = {}
    max_marker_residual_m: Annotated[float, _between(0.001, 1.0)] = 0.02
    calibrate_s: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    lab_up: Literal["x", "y", "z", "-x", "-y", "-z"] = "z"
    fit: Literal["positions", "segments"] = "positions"
    clusters: dict[str, Annotated[list[str], Field(min_length=3)]] = {}
    scale_segments: list[str] = []
    held_s: dict[str, list[Annotated[list[float], Field(min_length=2, max_length=2)]]] = {}
    bvh: BvhSpec = BvhSpec()

    @field_validator("calibrate_s")
    @classmethod
    def _calibration(cls, value: list[float] | None) -> list[float] | None:
        if value is not None and not value[0] <= value[1]:
            raise ValueError("a window [start, end] with start <= end [s]")
        return value

    @field_validator("held_s")
    @classmethod
    def _windows(cls, value: dict[str, list[list[float]]]) -> dict[str, list[list[float]]]:
        for name, windows in value.items():
            for start, end in windows:
                if not start < end:
                    raise ValueError(f"{name}: a window [start, end] with start < end [s]")
        return value

    @field_validator("markers")
    @classmethod
    def _three_landmarks(cls, value: dict[str, list[str]]) -> dict[str, list[str]]:
        if len(value) < 3:
            raise ValueError("at least 3 landmarks, each mapped to a list of marker labels")
        return value

    @field_validator("markers", "clusters")
    @classmethod
    def _labels_once(cls, value: dict[str, list[str]]) -> dict[str, list[str]]:
        for name, labels in value.items():
            twice = next((label for label in labels if labels.count(label) > 1), None)
            if twice is not None:
                count = labels.count(twice)
                raise ValueError(f"{name}: each label once ({twice!r} is there {count} times)")
        return value


class SolverSpec(Strict):
    """IK solver and its options; an option left out takes the solver's own default."""

    name: Literal["nullspace", "lexicographic"] = "lexicographic"
    max_iterations: Annotated[int, Field(ge=1, le=MAX_SOLVER_ITERATIONS)] | None = None
    tolerance: Annotated[float, _between(MIN_TOLERANCE, MAX_TOLERANCE)] | None = None
    damping: Annotated[float, _between(0.0, 10.0)] | None = None

    @model_validator(mode="after")
    def _damping(self) -> SolverSpec:
        if self.damping is not None and self.name != "nullspace":
            raise ValueError("damping only with name = 'nullspace'")
        return self


class ProblemSpec(Strict):
    """A whole problem file."""

    title: str = ""
    description: str = ""
    body: BodySpec
    posture_deg: dict[str, Angle] = {}
    loads: list[LoadSpec] = []
    tasks: list[Task] = []
    fatigue: FatigueSpec = FatigueSpec()
    simulation: SimulationSpec = SimulationSpec()
    schedule: ScheduleSpec | None = None
    solver: SolverSpec = SolverSpec()
    ergonomics: ErgonomicsSpec = ErgonomicsSpec()
    motion: MotionSpec = MotionSpec()
