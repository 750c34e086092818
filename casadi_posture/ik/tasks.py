"""IK tasks: data plus a CasADi residual e(q, p), zero when the task is achieved (docs/model.md).

A task knows nothing of the solvers. Its targets are CasADi parameters ``p``
(so a solver is built once and the targets change freely); its geometry
(directions, normals, axes) is fixed data. ``step_limit`` bounds the task error
a linearised solver may try to remove in one iteration, in the task's units.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture.biomech.comfort import ComfortMeasure, comfort_measure
from casadi_posture.biomech.passive import PassiveTorque
from casadi_posture.biomech.strength import Strength
from casadi_posture.biomech.torques import comfort_strengths, torque_expressions
from casadi_posture.body.loads import LOAD_PARAMETERS, Load, pack
from casadi_posture.body.tree import BodyModel
from casadi_posture.spec.schema import (
    ComfortTask,
    ComTask,
    FeetTask,
    GazeTask,
    LineTask,
    OrientationTask,
    PlaneTask,
    PositionTask,
    PostureTask,
)
from casadi_posture.spec.schema import Task as TaskSpec

#: Largest task error removed per linearised iteration: 0.1 m (Buss's error clamping,
#: in Buss's damped least squares) and 0.3 rad for angular tasks.
CARTESIAN_STEP = 0.1
ANGULAR_STEP = 0.3


@dataclass(frozen=True)
class Task:
    """Base of all tasks: a name and a priority level (1 = highest)."""

    name: str
    priority: int

    step_limit = CARTESIAN_STEP
    unit = "m"

    def targets(self) -> np.ndarray:
        """Numeric values of the task's parameters."""
        raise NotImplementedError

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        """Residual e(q, p) as a column; ``p`` holds ``targets``."""
        raise NotImplementedError


@dataclass(frozen=True)
class Position(Task):
    """Effector at a point: e = x(q) - target [m]."""

    effector: str
    target: tuple[float, float, float]

    def targets(self) -> np.ndarray:
        return np.array(self.target, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        return body.landmark(self.effector) - p


@dataclass(frozen=True)
class Offset(Task):
    """Effector at an offset from another landmark, the ``anchor``: e = x(q) − x_anchor(q) −
    target [m] (a segment's vector between two joint centres, say)."""

    effector: str
    anchor: str
    target: tuple[float, float, float]

    def targets(self) -> np.ndarray:
        return np.array(self.target, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        return body.landmark(self.effector) - body.landmark(self.anchor) - p


@dataclass(frozen=True)
class Line(Task):
    """Effector on a line through ``point`` along ``direction``: the offset from the line in
    an orthonormal basis of the plane normal to it (2 rows) [m]."""

    effector: str
    point: tuple[float, float, float]
    direction: tuple[float, float, float]

    def targets(self) -> np.ndarray:
        return np.array(self.point, dtype=float)

    def helper_axis(self) -> int:
        """The world axis most nearly normal to the line, which ``normal_rows`` starts
        from (kept when the direction changes a little, so the rows change smoothly)."""
        return int(np.argmin(np.abs(np.asarray(self.direction, dtype=float))))

    def normal_basis(self) -> np.ndarray:
        """2×3 orthonormal rows spanning the plane normal to the line."""
        rows = normal_rows(ca.DM(self.direction), self.helper_axis())
        return np.array(rows, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        return ca.DM(self.normal_basis()) @ (body.landmark(self.effector) - p)


@dataclass(frozen=True)
class Plane(Task):
    """Effector on a plane through ``point`` with ``normal``: signed distance [m]."""

    effector: str
    point: tuple[float, float, float]
    normal: tuple[float, float, float]

    def targets(self) -> np.ndarray:
        return np.array(self.point, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        n = np.asarray(self.normal, dtype=float)
        return ca.DM(n / np.linalg.norm(n)).T @ (body.landmark(self.effector) - p)


@dataclass(frozen=True)
class Orientation(Task):
    """Frame of a segment at a target orientation: e = ½·vee(Rtᵀ R - Rᵀ Rt), which is
    sin(angle)·axis of the error rotation [rad-like], zero at R = Rt."""

    segment: str
    dof: str | None
    rotation: tuple[float, ...]

    step_limit = ANGULAR_STEP
    unit = "rad"

    def targets(self) -> np.ndarray:
        return np.array(self.rotation, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        target = ca.reshape(p, 3, 3)
        r = body.rotation(self.dof)
        skew = 0.5 * (target.T @ r - r.T @ target)
        return ca.vertcat(skew[2, 1], skew[0, 2], skew[1, 0])


@dataclass(frozen=True)
class Frame(Orientation):
    """``Orientation``, axis by axis: e = vec(R − Rt), 9 rows, of norm 2√2·sin(angle/2)
    [rad-like]; zero only at R = Rt, where ``Orientation``'s error also vanishes at a half
    turn, a stationary point a solver can stop at (recorded motion)."""

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        return ca.reshape(body.rotation(self.dof) - ca.reshape(p, 3, 3), 9, 1)


@dataclass(frozen=True)
class CentreOfMass(Task):
    """Centre of mass of the body and the ``carried`` point masses (landmark, kg) over a
    target in the listed world axes [m] (balance). Its parameters are the target's
    coordinates, then the carried masses [kg] (so a held mass can change, or be
    differentiated with respect to, without rebuilding)."""

    target: tuple[float, float, float]
    axes: str
    carried: tuple[tuple[str, float], ...] = ()

    def targets(self) -> np.ndarray:
        point = [self.target["xyz".index(a)] for a in self.axes]
        return np.array(point + [m for _, m in self.carried], dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        k = len(self.axes)
        carried = [(at, p[k + i]) for i, (at, _) in enumerate(self.carried)]
        com = body.com(carried)
        return ca.vertcat(*[com["xyz".index(a)] for a in self.axes]) - p[:k]


@dataclass(frozen=True)
class Feet(Task):
    """Every foot carried by a DOF kept at its zero-posture place: the offset of its sole's
    centre [m] and the orientation error of its frame, ½·vee(Rᵀ - R) [rad-like] (zero at
    R = I), 6 rows per foot."""

    def targets(self) -> np.ndarray:
        return np.zeros(0)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        rows = []
        for foot in body.feet:
            if foot.dof is None:
                continue
            centre = foot.centre()
            r = body.rotation(foot.dof)
            skew = 0.5 * (r.T - r)
            rows += [body.point(foot.dof, ca.vertsplit(centre)) - centre]
            rows += [ca.vertcat(skew[2, 1], skew[0, 2], skew[1, 0])]
        return ca.vertcat(*rows)


@dataclass(frozen=True)
class Gaze(Task):
    """Look at a point: e = u(q) × (target − eye(q))/|target − eye(q)|, the sine of the angle
    between the segment's ``forward`` direction u and the line of sight, times its axis."""

    segment: str
    dof: str | None
    eye: str
    forward: tuple[float, float, float]
    target: tuple[float, float, float]

    step_limit = ANGULAR_STEP
    unit = "rad"

    def targets(self) -> np.ndarray:
        return np.array(self.target, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        u = np.asarray(self.forward, dtype=float)
        direction = body.rotation(self.dof) @ ca.DM(u / np.linalg.norm(u))
        sight = p - body.landmark(self.eye)
        return ca.cross(direction, sight / ca.norm_2(sight))


@dataclass(frozen=True)
class JointReference(Task):
    """Joints at reference angles: e = q[dofs] - reference [rad]."""

    dofs: tuple[str, ...]
    reference: tuple[float, ...]

    step_limit = ANGULAR_STEP
    unit = "rad"

    def targets(self) -> np.ndarray:
        return np.array(self.reference, dtype=float)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        return ca.vertcat(*[body.q[body.index[d]] for d in self.dofs]) - p


@dataclass(frozen=True)
class Comfort(Task):
    """How uncomfortable the posture is (biomech/comfort.py), the residual whose squared norm
    is the ``measure``: the criterion that settles what the levels above leave free, at the
    lowest level. Its parameters are the neutral posture [rad] and, when the measure counts
    effort, the loads (``pack``) and each half-joint's effort weight c_g (1 by default;
    1 + k·F_g under the whole-body fatigue adjustment), so neither rebuilds a solver."""

    measure: ComfortMeasure
    loads: tuple[Load, ...] = ()
    passive: Mapping[str, PassiveTorque] = field(default_factory=dict)
    strength: Mapping[str, Strength] = field(default_factory=dict)
    #: The active torque per DOF [N·m] of these loads and passive torques as an expression of
    #: ``body.q`` and a symbol for the loads (``pack``): a torque model's, taken with the
    #: level's own load parameters in place of the symbol instead of built again.
    active: tuple[ca.SX, ca.SX] | None = field(default=None, repr=False, compare=False)

    step_limit = ANGULAR_STEP
    unit = "1"

    def targets(self) -> np.ndarray:
        if not self.measure.effort:
            return np.array(self.measure.neutral, dtype=float)
        weights = np.ones(2 * self.measure.neutral.size)
        return np.concatenate([self.measure.neutral, pack(self.loads), weights])

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        n = body.n
        if not self.measure.effort:
            return self.measure.rows(body, body.q, p)
        loads = p[n : n + LOAD_PARAMETERS * len(self.loads)]
        if self.active is None:
            _, _, active, _ = torque_expressions(
                body, self.loads, loads, self.passive, self.strength
            )
        else:
            expression, symbol = self.active
            active = ca.substitute(expression, symbol, loads)
        strength = comfort_strengths(body, self.strength)
        weights = p[n + LOAD_PARAMETERS * len(self.loads) :]
        return self.measure.rows(body, body.q, p[:n], active, strength, weights)

    def effort_weights(self) -> slice:
        """Where the effort weights c_g lie in ``targets`` (an empty slice without effort)."""
        n = self.measure.neutral.size
        if not self.measure.effort:
            return slice(n, n)
        start = n + LOAD_PARAMETERS * len(self.loads)
        return slice(start, start + 2 * n)


def rotation_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw)·Ry(pitch)·Rx(roll) [rad]."""
    return np.array(rpy_matrix(roll, pitch, yaw), dtype=float)


def rpy_matrix(roll: Any, pitch: Any, yaw: Any) -> ca.DM | ca.SX:
    """Rz(yaw)·Ry(pitch)·Rx(roll) [rad] of numbers or CasADi expressions."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (ca.cos, ca.sin))
    rx = ca.blockcat([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = ca.blockcat([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = ca.blockcat([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def line_direction(spec: LineTask) -> tuple[float, float, float]:
    """The direction of a line task, from ``direction`` or elevation/azimuth [deg]."""
    if spec.direction is not None:
        return tuple(spec.direction)
    return direction_at(math.radians(spec.elevation_deg), math.radians(spec.azimuth_deg or 0.0))


def direction_at(elevation: Any, azimuth: Any) -> tuple[Any, Any, Any]:
    """The unit vector at ``elevation`` above the forward (x) horizontal, turned by
    ``azimuth`` about z [rad]: floats, or CasADi expressions of symbolic angles."""
    return (
        ca.cos(elevation) * ca.cos(azimuth),
        ca.cos(elevation) * ca.sin(azimuth),
        ca.sin(elevation),
    )


def normal_rows(direction: ca.DM | ca.SX, helper: int) -> ca.DM | ca.SX:
    """2×3 orthonormal rows spanning the plane normal to ``direction`` (3×1, any length),
    the first from world axis ``helper`` with its part along the line removed, the second
    their cross product; numbers or CasADi expressions alike."""
    d = direction / ca.norm_2(direction)
    axis = ca.DM.eye(3)[:, helper]
    n1 = axis - ca.dot(axis, d) * d
    n1 = n1 / ca.norm_2(n1)
    return ca.horzcat(n1, ca.cross(d, n1)).T


def _segment_dof(name: str, body: BodyModel) -> str | None:
    return next(s.dof for s in body.segments if s.name == name)


def task_from_spec(
    spec: TaskSpec,
    body: BodyModel,
    loads: Sequence[Load] = (),
    posture: np.ndarray | None = None,
    passive: Mapping[str, PassiveTorque] | None = None,
    strength: Mapping[str, Strength] | None = None,
) -> Task:
    """The task object of a validated problem-file task; a centre-of-mass task counts the
    masses of the held ``loads`` and without a target keeps the centre of mass where it is
    at ``posture`` [rad]; a comfort task's effort counts the ``loads`` with the body's
    ``passive`` torques and ``strength``."""
    base = {"name": spec.name, "priority": spec.priority}
    if isinstance(spec, ComfortTask):
        measure = comfort_measure(
            body,
            spec.measure,
            weights=spec.weights,
            joint_weights=spec.joint_weights,
            neutral_deg=spec.neutral_deg,
        )
        if measure.effort and (passive is None or strength is None):
            raise ValueError("a comfort task with effort needs the passive torques and strength")
        return Comfort(
            **base,
            measure=measure,
            loads=tuple(loads),
            passive=passive or {},
            strength=strength or {},
        )
    if isinstance(spec, PositionTask):
        return Position(**base, effector=spec.effector, target=tuple(spec.target_m))
    if isinstance(spec, LineTask):
        return Line(
            **base,
            effector=spec.effector,
            point=tuple(spec.point_m),
            direction=line_direction(spec),
        )
    if isinstance(spec, PlaneTask):
        return Plane(
            **base, effector=spec.effector, point=tuple(spec.point_m), normal=tuple(spec.normal)
        )
    if isinstance(spec, OrientationTask):
        dof = _segment_dof(spec.segment, body)
        rotation = rotation_rpy(*np.radians(spec.target_rpy_deg))
        return Orientation(
            **base, segment=spec.segment, dof=dof, rotation=tuple(rotation.ravel(order="F"))
        )
    if isinstance(spec, ComTask):
        carried = tuple((load.at, load.mass) for load in loads if load.mass > 0)
        task = CentreOfMass(
            **base,
            target=(0.0, 0.0, 0.0),
            axes=spec.axes,
            carried=carried if spec.include_loads else (),
        )
        if spec.target_m is not None:
            return replace(task, target=tuple(spec.target_m))
        whole = replace(task, axes="xyz")
        com = ca.Function("com", [body.q], [body.com(whole.carried)])
        at = np.zeros(body.n) if posture is None else posture
        return replace(task, target=tuple(np.asarray(com(at)).ravel()))
    if isinstance(spec, FeetTask):
        return Feet(**base)
    if isinstance(spec, GazeTask):
        return Gaze(
            **base,
            segment=spec.segment,
            dof=_segment_dof(spec.segment, body),
            eye=spec.eye,
            forward=tuple(spec.forward),
            target=tuple(spec.target_m),
        )
    if isinstance(spec, PostureTask):
        return JointReference(
            **base,
            dofs=tuple(spec.reference_deg),
            reference=tuple(math.radians(v) for v in spec.reference_deg.values()),
        )
    raise TypeError(f"unknown task spec {type(spec).__name__}")


def tasks_from_specs(
    specs: Sequence[TaskSpec],
    body: BodyModel,
    loads: Sequence[Load] = (),
    posture: np.ndarray | None = None,
    passive: Mapping[str, PassiveTorque] | None = None,
    strength: Mapping[str, Strength] | None = None,
) -> list[Task]:
    return [task_from_spec(s, body, loads, posture, passive, strength) for s in specs]
