"""The problem-file format (TOML), validated with pydantic; ``problems/README.md`` documents it.

Key names carry their unit (``_m``, ``_kg``, ``_deg``, ``_s``, ``_Nm``,
``_pct_mvc``); angles in files are degrees. Unknown keys are errors.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    field_validator,
    model_validator,
)

Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Pair = Annotated[list[float], Field(min_length=2, max_length=2)]
Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]
Priority = Annotated[int, Field(ge=1)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)


def _increasing(pair: list[float]) -> list[float]:
    if not pair[0] < pair[1]:
        raise ValueError("[min, max] with min < max")
    return pair


def _nonzero(vector: list[float]) -> list[float]:
    if sum(c * c for c in vector) < 1e-24:
        raise ValueError("a non-zero vector")
    return vector


class ExponentialPassiveSpec(Strict):
    """τp = k1·exp(-k2·(q - q1)) - k3·exp(-k4·(q2 - q)); every key required."""

    model: Literal["exponential"] = "exponential"
    k1_Nm: NonNegative
    k2_per_rad: NonNegative
    q1_deg: float
    k3_Nm: NonNegative
    k4_per_rad: NonNegative
    q2_deg: float


class NoPassiveSpec(Strict):
    model: Literal["none"]


def _passive_model(value: object) -> str:
    """The passive model's tag; a table without ``model`` is the exponential default."""
    if isinstance(value, dict):
        return value.get("model", "exponential")
    return getattr(value, "model", "exponential")


PassiveSpec = Annotated[
    Annotated[ExponentialPassiveSpec, Tag("exponential")] | Annotated[NoPassiveSpec, Tag("none")],
    Discriminator(_passive_model),
]


class DofSpec(Strict):
    range_deg: Pair | None = None
    passive: PassiveSpec | None = None

    _range = field_validator("range_deg")(lambda v: v if v is None else _increasing(v))


class SegmentSpec(Strict):
    mass_kg: NonNegative | None = None
    length_m: Positive | None = None
    com_fraction: Annotated[float, Field(ge=0, le=1)] | None = None


class StrengthCurveSpec(Strict):
    dof: str
    angle_deg: list[float] = Field(min_length=2)
    strength_Nm: list[Positive] = Field(min_length=2)

    @model_validator(mode="after")
    def _table(self) -> StrengthCurveSpec:
        if len(self.angle_deg) != len(self.strength_Nm):
            raise ValueError("angle_deg and strength_Nm of the same length")
        if any(b <= a for a, b in zip(self.angle_deg, self.angle_deg[1:], strict=False)):
            raise ValueError("angle_deg strictly increasing")
        return self


class HalfJointSpec(Strict):
    strength_Nm: Positive | None = None
    strength_curve: StrengthCurveSpec | None = None

    @model_validator(mode="after")
    def _one(self) -> HalfJointSpec:
        if self.strength_Nm is not None and self.strength_curve is not None:
            raise ValueError("either strength_Nm or strength_curve, not both")
        return self


class BodySpec(Strict):
    model: str
    sex: Literal["male", "female"] = "male"
    stature_m: Annotated[float, Field(gt=0.5, lt=2.5)] = 1.741
    mass_kg: Annotated[float, Field(gt=10, lt=300)] = 73.0
    age_years: Annotated[float, Field(ge=18, le=100)] = 30.0
    dofs: dict[str, DofSpec] = {}
    segments: dict[str, SegmentSpec] = {}
    half_joints: dict[str, HalfJointSpec] = {}


class LoadSpec(Strict):
    name: str
    at: str
    mass_kg: NonNegative = 0.0
    force_N: Vec3 = (0.0, 0.0, 0.0)
    moment_Nm: Vec3 = (0.0, 0.0, 0.0)


class _Task(Strict):
    name: str
    priority: Priority


class PositionTask(_Task):
    kind: Literal["position"]
    effector: str
    target_m: Vec3


class LineTask(_Task):
    """Attraction of an effector to a line through ``point_m``, along ``direction`` or
    at ``elevation_deg`` above the forward horizontal, turned by ``azimuth_deg`` about z."""

    kind: Literal["line"]
    effector: str
    point_m: Vec3
    direction: Vec3 | None = None
    elevation_deg: Annotated[float, Field(ge=-90, le=90)] | None = None
    azimuth_deg: float | None = None

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
    point_m: Vec3
    normal: Vec3

    _normal = field_validator("normal")(_nonzero)


class OrientationTask(_Task):
    """Orientation of a segment's frame, as roll-pitch-yaw about the world x, y, z [deg]."""

    kind: Literal["orientation"]
    segment: str
    target_rpy_deg: Vec3


class ComTask(_Task):
    """Whole-body centre of mass over a point, in the listed world axes (balance)."""

    kind: Literal["com"]
    target_m: Vec3
    axes: Literal["x", "y", "z", "xy", "xz", "yz", "xyz"] = "xyz"


class PostureTask(_Task):
    kind: Literal["posture"]
    reference_deg: dict[str, float]


Task = Annotated[
    PositionTask | LineTask | PlaneTask | OrientationTask | ComTask | PostureTask,
    Field(discriminator="kind"),
]


class FatigueSpec(Strict):
    endurance: str = "manenica"
    model: str = "holding_time"
    fatigue_threshold: Annotated[float, Field(gt=0, le=1)] = 0.8
    recovery_threshold: Annotated[float, Field(gt=0, le=1)] = 0.5
    strategy: Literal["active", "passive"] = "active"
    r_min: Annotated[float, Field(ge=0, le=1)] = 0.9
    load_threshold_pct_mvc: Annotated[float, Field(ge=0, le=100)] | None = None
    epsilon_Nm: Positive = 0.05
    beta: Annotated[float, Field(gt=0, lt=1)] = 0.5
    max_step_deg: Positive = 1.0
    alpha_rad_per_Nm2: Annotated[float, Field(lt=0)] = -1e-4

    @model_validator(mode="after")
    def _thresholds(self) -> FatigueSpec:
        if not self.recovery_threshold < self.fatigue_threshold:
            raise ValueError(
                "0 < recovery_threshold < fatigue_threshold <= 1, got recovery_threshold = "
                f"{self.recovery_threshold:g} and fatigue_threshold = {self.fatigue_threshold:g}"
            )
        if self.load_threshold_pct_mvc is not None and self.model != "holding_time":
            raise ValueError("load_threshold_pct_mvc only with model = 'holding_time'")
        return self


class SimulationSpec(Strict):
    duration_s: Positive = 600.0
    time_step_s: Positive = 1.0

    @model_validator(mode="after")
    def _step(self) -> SimulationSpec:
        if self.time_step_s > self.duration_s:
            raise ValueError(
                f"time_step_s <= duration_s, got {self.time_step_s:g} s > {self.duration_s:g} s"
            )
        return self


class SolverSpec(Strict):
    """IK solver and its options; an option left out takes the solver's own default."""

    name: Literal["nullspace", "lexicographic"] = "lexicographic"
    max_iterations: Annotated[int, Field(ge=1)] | None = None
    tolerance: Positive | None = None
    damping: NonNegative | None = None

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
    posture_deg: dict[str, float] = {}
    loads: list[LoadSpec] = []
    tasks: list[Task] = []
    fatigue: FatigueSpec = FatigueSpec()
    simulation: SimulationSpec = SimulationSpec()
    solver: SolverSpec = SolverSpec()
