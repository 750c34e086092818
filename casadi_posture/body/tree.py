"""Kinematic tree of revolute degrees of freedom as CasADi expressions (docs/model.md).

Everything is described at the zero posture, in the world frame: each DOF by
its joint centre and axis, each segment by its mass and centre of mass, each
landmark by its position. At the zero posture every body frame is aligned
with the world, so a DOF's axis in its parent's frame equals its world axis
at zero, and forward kinematics is a product of exponentials:

    R_j(q) = R_parent(q) · Rot(axis_j, q_j)
    o_j(q) = o_parent(q) + R_parent(q) · (origin_j - origin_parent)
    x(q)   = o_j(q) + R_j(q) · (x0 - origin_j)        for a point x0 carried by DOF j

Jacobians come from CasADi's algorithmic differentiation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.errors import ProblemError

Vector3 = tuple[float, float, float]


def column(values: Sequence[float | ca.SX]) -> ca.DM | ca.SX:
    """A point or vector [m] as a CasADi column: DM of numbers, SX where a coordinate is a
    symbol (a body whose geometry depends on parameters, as sensitivities build it)."""
    return ca.vertcat(*values)


#: The joint regions a muscle group's endurance and recovery data are filed under: those
#: with data of their own (Frey-Law & Avin's fits in data/endurance.toml) and the hip, whose
#: groups take the general fit.
REGIONS = ("general", "shoulder", "elbow", "hand", "trunk", "hip", "knee", "ankle")


@dataclass(frozen=True)
class Dof:
    """A revolute degree of freedom and its two half-joints (antagonistic muscle groups).

    ``origin`` [m] and ``axis`` are in the world frame at the zero posture (numbers; the
    origin, a segment's mass and centre of mass, a landmark's and a sole's points may be
    CasADi symbols: every expression of the body is then one of them too);
    ``lower``/``upper`` [rad] bound the angle. ``positive`` is the muscle group
    that drives the angle up, ``negative`` the one that drives it down;
    ``regions`` names the joint region of each one's endurance data (positive, negative).
    """

    name: str
    parent: str | None
    origin: Vector3
    axis: Vector3
    lower: float
    upper: float
    positive: str
    negative: str
    regions: tuple[str, str] = ("general", "general")


@dataclass(frozen=True)
class Segment:
    """A rigid segment: ``mass`` [kg], centre of mass ``com`` [m, world, zero posture].

    ``dof`` is the DOF whose frame carries it (``None``: fixed to the world);
    ``proximal`` and ``distal`` name the landmarks at its end points, if any.
    """

    name: str
    dof: str | None
    mass: float
    com: Vector3
    proximal: str | None = None
    distal: str | None = None


@dataclass(frozen=True)
class Landmark:
    """A named point of the body (joint centre, effector) [m, world, zero posture]."""

    name: str
    dof: str | None
    position: Vector3


@dataclass(frozen=True)
class Foot:
    """A foot on the floor: the ``outline`` of its sole [m, world, zero posture], carried by
    ``dof`` (``None``: fixed to the world)."""

    name: str
    dof: str | None
    outline: tuple[Vector3, ...]

    def centre(self) -> ca.DM | ca.SX:
        """The mean of the sole's outline [m, world, zero posture]."""
        return sum(column(p) for p in self.outline) / len(self.outline)


@dataclass(frozen=True)
class HalfJoint:
    """One muscle group of a DOF: ``sign`` +1 if it drives the angle up, -1 if down."""

    name: str
    dof: str
    dof_index: int
    sign: int
    region: str


def rotation(axis: np.ndarray, angle: ca.SX) -> ca.SX:
    """Rotation matrix about a unit ``axis`` by ``angle`` [rad] (Rodrigues' formula)."""
    k = ca.SX(
        np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    )
    return ca.SX.eye(3) + ca.sin(angle) * k + (1.0 - ca.cos(angle)) * (k @ k)


class BodyModel:
    """A kinematic tree with its symbolic joint vector ``q`` [rad] and forward kinematics."""

    def __init__(
        self,
        name: str,
        dofs: Sequence[Dof],
        segments: Sequence[Segment],
        landmarks: Sequence[Landmark],
        *,
        gravity: float,
        feet: Sequence[Foot] = (),
    ) -> None:
        self.name = name
        self.dofs = tuple(dofs)
        self.segments = tuple(segments)
        self.landmarks = {lm.name: lm for lm in landmarks}
        self.feet = tuple(feet)
        self.gravity = gravity
        self._check()
        self.index = {d.name: i for i, d in enumerate(self.dofs)}
        self._half_joints: tuple[HalfJoint, ...] | None = None
        self.q = ca.SX.sym("q", len(self.dofs))
        self._rotation: dict[str | None, ca.SX] = {None: ca.SX.eye(3)}
        self._origin: dict[str | None, ca.SX] = {None: ca.SX.zeros(3)}
        self._origin0: dict[str | None, ca.DM | ca.SX] = {None: ca.DM.zeros(3)}
        for i, dof in enumerate(self.dofs):
            r_parent = self._rotation[dof.parent]
            origin0 = column(dof.origin)
            offset = origin0 - self._origin0[dof.parent]
            self._origin[dof.name] = self._origin[dof.parent] + r_parent @ offset
            self._rotation[dof.name] = r_parent @ rotation(self.axis(dof.name), self.q[i])
            self._origin0[dof.name] = origin0

    def _check(self) -> None:
        seen: set[str] = set()
        for dof in self.dofs:
            if dof.name in seen:
                raise ProblemError(None, "body.dofs", dof.name, "unique DOF names")
            if dof.parent is not None and dof.parent not in seen:
                raise ProblemError(
                    None,
                    f"body.dofs.{dof.name}.parent",
                    dof.parent,
                    "a DOF defined before it (the tree in topological order)",
                )
            if np.linalg.norm(dof.axis) < 1e-12:
                raise ProblemError(None, f"body.dofs.{dof.name}.axis", dof.axis, "a non-zero axis")
            if not dof.lower < dof.upper:
                raise ProblemError(
                    None,
                    f"body.dofs.{dof.name}.range_deg",
                    [np.degrees(dof.lower), np.degrees(dof.upper)],
                    "min < max",
                )
            seen.add(dof.name)
        carried = [(f"body.segments.{s.name}", s.dof) for s in self.segments]
        carried += [(f"body.landmarks.{lm.name}", lm.dof) for lm in self.landmarks.values()]
        carried += [(f"body.feet.{foot.name}", foot.dof) for foot in self.feet]
        for key, dof_name in carried:
            if dof_name is not None and dof_name not in seen:
                raise ProblemError(None, f"{key}.dof", dof_name, f"one of {sorted(seen)}")
        for segment in self.segments:
            if not isinstance(segment.mass, ca.SX) and segment.mass < 0:
                raise ProblemError(
                    None, f"body.segments.{segment.name}.mass_kg", segment.mass, "a mass >= 0"
                )

    @property
    def n(self) -> int:
        """Number of DOFs."""
        return len(self.dofs)

    @property
    def dof_names(self) -> list[str]:
        return [d.name for d in self.dofs]

    @property
    def lower(self) -> np.ndarray:
        """Lower joint limits [rad]."""
        return np.array([d.lower for d in self.dofs])

    @property
    def upper(self) -> np.ndarray:
        """Upper joint limits [rad]."""
        return np.array([d.upper for d in self.dofs])

    @property
    def half_joints(self) -> list[HalfJoint]:
        """The two half-joints of every DOF, positive first, in DOF order (built once)."""
        if self._half_joints is None:
            self._half_joints = tuple(
                HalfJoint(name, dof.name, i, sign, region)
                for i, dof in enumerate(self.dofs)
                for name, sign, region in (
                    (dof.positive, +1, dof.regions[0]),
                    (dof.negative, -1, dof.regions[1]),
                )
            )
        return list(self._half_joints)

    @property
    def total_mass(self) -> float:
        """Mass of all segments [kg]."""
        return float(sum(s.mass for s in self.segments))

    @property
    def planar(self) -> bool:
        """Whether the body moves in one plane: every DOF axis parallel to the first."""
        first = self.axis(self.dofs[0].name)
        return all(np.linalg.norm(np.cross(first, self.axis(d.name))) < 1e-9 for d in self.dofs)

    def axis(self, dof: str) -> np.ndarray:
        """Unit axis of ``dof`` in the world frame at the zero posture."""
        a = np.asarray(self.dofs[self.index[dof]].axis, dtype=float)
        return a / np.linalg.norm(a)

    def ancestors(self, dof: str | None) -> list[str]:
        """The DOFs that move the frame of ``dof``, root first, ``dof`` included."""
        chain: list[str] = []
        while dof is not None:
            chain.append(dof)
            dof = self.dofs[self.index[dof]].parent
        return chain[::-1]

    def joint_centre(self, dof: str) -> ca.SX:
        """World position [m] of the centre of ``dof``."""
        return self._origin[dof]

    def joint_axis(self, dof: str) -> ca.SX:
        """World direction of the axis of ``dof`` (unit)."""
        return self._rotation[dof] @ ca.DM(self.axis(dof))

    def rotation(self, dof: str | None) -> ca.SX:
        """Orientation of the frame of ``dof`` in the world (3×3, SX)."""
        return self._rotation[dof]

    def point(self, dof: str | None, position0: Sequence[float]) -> ca.SX:
        """World position [m] of a point carried by ``dof``, given at the zero posture."""
        x0 = column(position0) - self._origin0[dof]
        return self._origin[dof] + self._rotation[dof] @ x0

    def landmark(self, name: str) -> ca.SX:
        """World position [m] of a landmark."""
        lm = self.landmarks[name]
        return self.point(lm.dof, lm.position)

    def segment_com(self, segment: Segment) -> ca.SX:
        """World position [m] of a segment's centre of mass."""
        return self.point(segment.dof, segment.com)

    def com(self, carried: Sequence[tuple[str, float]] = ()) -> ca.SX:
        """Centre of mass [m] of the body and the ``carried`` point masses (landmark, kg)."""
        weighted = sum((s.mass * self.segment_com(s) for s in self.segments), ca.SX.zeros(3))
        weighted += sum((m * self.landmark(at) for at, m in carried), ca.SX.zeros(3))
        return weighted / (sum(s.mass for s in self.segments) + sum(m for _, m in carried))

    def angular_jacobian(self, dof: str | None) -> ca.SX:
        """3×n map from joint rates to the angular velocity of the frame of ``dof``."""
        columns = [ca.SX.zeros(3) for _ in self.dofs]
        for name in self.ancestors(dof):
            parent = self.dofs[self.index[name]].parent
            columns[self.index[name]] = self._rotation[parent] @ ca.DM(self.axis(name))
        return ca.horzcat(*columns)

    def jacobian(self, expression: ca.SX) -> ca.SX:
        """Jacobian of an expression of ``q`` by algorithmic differentiation."""
        return ca.jacobian(expression, self.q)
