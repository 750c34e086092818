"""A problem as one CasADi graph of its numeric inputs: every priority level's residual, the
active torque and strength of every group, and every group's endurance law, as expressions
of the posture ``q`` [rad] and a vector ``theta`` of named inputs (docs/sensitivity.md).

The inputs are the problem's numbers: load masses, forces and moments; task targets;
stature, body mass, age (and the seat's height) of a built-in body; every constant strength;
the passive curves' coefficients; the endurance and recovery laws' coefficients; and the
posture the file starts from where a centre-of-mass task keeps the centre of mass where that
posture has it.

A built-in body's joint centres, segment masses and centres of mass, landmarks, soles and
default strengths depend on stature, body mass and age through linear scalings (de Leva
fractions, ANSUR II and Reed ratios, the Harbo et al. regressions) and the product m·g·h
(Anderson et al. 2007), each linear in every one of them. Their slopes are read off the
model builder at the problem's body, and the builder is checked to be linear there (the
change over +Δ is that over −Δ to 1e-9): an input it is not linear in is left out, with
the reason in ``ParametricProblem.left_out``.
"""

from __future__ import annotations

import math
import typing
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, Literal

import casadi as ca
import numpy as np

from casadi_posture.biomech.low_back import has_lumbar_joint, low_back_expressions, moment_arms
from casadi_posture.biomech.passive import ExponentialPassive, PassiveTorque, ReshapedPassive
from casadi_posture.biomech.shape import numbers, rebuilt
from casadi_posture.biomech.strength import ConstantStrength, ScaledCurveStrength, Strength
from casadi_posture.biomech.torques import comfort_strengths, torque_expressions
from casadi_posture.body.loads import LOAD_PARAMETERS, pack
from casadi_posture.data.parameters import Parameter
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.tasks import (
    CentreOfMass,
    Comfort,
    Gaze,
    JointReference,
    Line,
    Orientation,
    Plane,
    Position,
    Task,
    direction_at,
    normal_rows,
    rpy_matrix,
)
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.static import SCHEDULE_NOTE

Kind = Literal["load", "target", "posture", "body", "strength", "passive", "endurance"]
KINDS: tuple[Kind, ...] = typing.get_args(Kind)

#: Body inputs of a built-in model: problem-file key and unit.
BODY_INPUTS = (
    ("body.stature_m", "m"),
    ("body.mass_kg", "kg"),
    ("body.age_years", "years"),
    ("body.hip_height_m", "m"),
)
#: Relative change of a body input at which the builder's linearity is checked.
BODY_STEP = 0.01
#: The builder is linear in a body input when its second difference is at most this, relative.
LINEARITY_TOLERANCE = 1e-9

_PASSIVE_KEYS = (("k1", "N·m"), ("k2", "1/rad"), ("q1", "deg"))
_PASSIVE_KEYS += (("k3", "N·m"), ("k4", "1/rad"), ("q2", "deg"))
_LOAD_KEYS = ("mass_kg", *(f"force_N[{k}]" for k in range(3)))
_LOAD_KEYS += tuple(f"moment_Nm[{k}]" for k in range(3))
_LOAD_UNITS = ("kg", "N", "N", "N", "N·m", "N·m", "N·m")


@dataclass(frozen=True)
class Input:
    """One numeric input: its ``key`` (a problem-file key, as ``--vary`` and overrides take
    it, or a shipped record's name), its value in ``unit`` and its kind."""

    key: str
    value: float
    unit: str
    kind: Kind


class ParametricProblem:
    """The graph of one problem: ``q`` [rad], ``theta`` (``inputs`` in order, at ``values``),
    ``levels`` (one residual per priority level of ``hierarchy``), ``tau_act`` [N·m] per DOF,
    ``strength`` [N·m], ``load`` [%MVC] and ``endurance`` [s] per half-joint (each group's
    law at its load, meaningful where the group is limited; None: the law has no
    expression), ``compression`` [N] at L5/S1 (None: the body has no lumbar joint). With
    ``symbolic=False`` there are no inputs: the same graph with the problem's numbers
    (``theta`` is empty)."""

    def __init__(
        self, problem: Problem, hierarchy: TaskHierarchy | None, *, symbolic: bool = True
    ) -> None:
        self.problem = problem
        self.symbolic = symbolic
        self.inputs: list[Input] = []
        self.left_out: dict[str, str] = {}
        if problem.spec.schedule is not None:
            self.left_out["schedule"] = SCHEDULE_NOTE
        self._symbols: list[ca.SX] = []
        self._records: dict[str, ca.SX] = {}
        slopes = self._body_slopes() if symbolic and problem.spec.body.tree is None else {}
        numbers = [ca.SX(v) for v in _numbers(problem)]
        for (key, value, unit), slope in slopes.items():
            x = self._input(key, value, unit, "body")
            numbers = [n + s * (x - value) if s else n for n, s in zip(numbers, slope, strict=True)]
        groups = len(problem.body.half_joints)
        self.body = rebuilt(problem.body, numbers[:-groups]) if slopes else problem.body
        self.q = self.body.q
        strengths = self._strengths(numbers[-groups:])
        passive = {d.name: self._passive(d.name) for d in self.body.dofs}
        loads = self._loads()
        self.tau_ext, _, self.tau_act, self.strength = torque_expressions(
            self.body, problem.loads, loads, passive, strengths
        )
        self.comfort_strength = comfort_strengths(self.body, strengths)
        self._load_masses = [loads[LOAD_PARAMETERS * k] for k in range(len(problem.loads))]
        self.compression = (
            low_back_expressions(self.body, problem.loads, loads, *moment_arms())[0]
            if has_lumbar_joint(self.body)
            else None
        )
        self.levels = [] if hierarchy is None else self._levels(hierarchy)
        self.load = self._load_pct_mvc()
        self.endurance = [self._endurance(k, self.load[k]) for k in range(self.load.numel())]
        self.theta = ca.vertcat(*self._symbols) if self._symbols else ca.SX(0, 1)
        self.values = np.array([i.value for i in self.inputs], dtype=float)

    # -- inputs ---------------------------------------------------------------------------

    def _input(self, key: str, value: float, unit: str, kind: Kind) -> ca.SX | float:
        """A new named input: its symbol (its value when the graph is not symbolic)."""
        if not self.symbolic:
            return value
        symbol = ca.SX.sym(key)
        self.inputs.append(Input(key, float(value), unit, kind))
        self._symbols.append(symbol)
        return symbol

    def record(self, record: Parameter) -> ca.SX | float:
        """A shipped record's value as an input (one per name; a list: one per item)."""
        if not self.symbolic:
            return record.value
        if record.name not in self._records:
            values = np.atleast_1d(np.asarray(record.value, dtype=float))
            if np.ndim(record.value) == 0:
                self._records[record.name] = self._input(
                    record.name, values[0], record.unit, "endurance"
                )
            else:
                self._records[record.name] = ca.vertcat(
                    *[
                        self._input(f"{record.name}[{k}]", v, record.unit, "endurance")
                        for k, v in enumerate(values)
                    ]
                )
        return self._records[record.name]

    def _body_slopes(self) -> dict[tuple[str, float, str], np.ndarray]:
        """The slope of every geometry number and strength in each body input the builder
        is linear in, keyed by (key, value, unit)."""
        problem = self.problem
        base = _numbers(problem)
        out = {}
        for key, unit in BODY_INPUTS:
            value = getattr(problem.spec.body, key.split(".")[1])
            if value is None:
                continue
            step = BODY_STEP * value
            plus, minus = (
                _numbers(problem_from_data(problem.data, problem.path, {key: value + s}))
                for s in (step, -step)
            )
            curvature = np.abs(plus + minus - 2 * base)
            if np.any(curvature > LINEARITY_TOLERANCE * np.maximum(1.0, np.abs(base))):
                self.left_out[key] = (
                    f"the body is not linear in it at {value:g} {unit} (a table switches "
                    "between the values around it)"
                )
                continue
            out[(key, value, unit)] = (plus - minus) / (2 * step)
        return out

    def _strengths(self, scaled: list[ca.SX]) -> dict[str, Strength]:
        """Each constant strength as an input, plus its change with the body inputs
        (``scaled``: the strengths as the body inputs make them)."""
        problem, out = self.problem, {}
        for k, half in enumerate(problem.body.half_joints):
            model = problem.strength[half.name]
            shipped_scale = isinstance(model, ScaledCurveStrength) or (
                isinstance(model, ConstantStrength) and model.comfort_fraction != 1.0
            )
            if shipped_scale:
                # a shipped curve, or a shipped value with the comfort measure's own scale: its
                # scale is the input, as the file's strength_scale sets it
                key = _strength_key(problem, k, "strength_scale")
                x = self._input(key, _scale(problem, k), "1", "strength")
                base = scaled[k] / _scale(problem, k)
                out[half.name] = replace(model, value=base * x)
                continue
            if not isinstance(model, ConstantStrength):
                out[half.name] = model
                self.left_out.setdefault(
                    f"strength.{half.name}", "a strength curve (its points are not inputs)"
                )
                continue
            ratio = _ratio(problem, k)
            if ratio is not None:
                # a ratio to the body's elbow flexion: the ratio is the input
                key = _strength_key(problem, k, "strength_ratio")
                x = self._input(key, ratio, "1", "strength")
                out[half.name] = replace(model, value=scaled[k] * x / ratio)
                continue
            key = _strength_key(problem, k)
            x = self._input(key, model.value, "N·m", "strength")
            out[half.name] = replace(model, value=x + (scaled[k] - model.value))
        return out

    def _passive(self, dof: str) -> PassiveTorque:
        """A DOF's passive curve with its six exponential coefficients as inputs."""
        model = self.problem.passive[dof]
        base = model.base if isinstance(model, ReshapedPassive) else model
        if not isinstance(base, ExponentialPassive):
            return model
        values = {}
        for name, unit in _PASSIVE_KEYS:
            value = getattr(base, name)
            if unit == "deg":
                degrees = self._input(
                    f"joints.{dof}.passive.{name}", math.degrees(value), unit, "passive"
                )
                values[name] = degrees * (math.pi / 180.0)
            else:
                values[name] = self._input(f"joints.{dof}.passive.{name}", value, unit, "passive")
        curve = ExponentialPassive(**values)
        return replace(model, base=curve) if isinstance(model, ReshapedPassive) else curve

    def _loads(self) -> ca.SX:
        """The load vector (7 per load) of inputs."""
        values = pack(self.problem.loads)
        entries = [
            self._input(f"loads[{k}].{name}", values[LOAD_PARAMETERS * k + j], unit, "load")
            for k in range(len(self.problem.loads))
            for j, (name, unit) in enumerate(zip(_LOAD_KEYS, _LOAD_UNITS, strict=True))
        ]
        return ca.vertcat(*entries) if entries else ca.SX(0, 1)

    def _levels(self, hierarchy: TaskHierarchy) -> list[ca.SX]:
        """Every level's residual with the tasks' targets as inputs."""
        specs = [t.name for t in self.problem.spec.tasks]
        out = []
        for level in hierarchy.levels:
            rows = [self._residual(task, specs.index(task.name)) for task in level]
            out.append(ca.vertcat(*rows))
        return out

    def _residual(self, task: Task, i: int) -> ca.SX:
        """Task ``i``'s residual with its targets as inputs (a line's direction too); the
        comfort level's effort on the torques and strengths of this graph."""
        if isinstance(task, Line):
            return self._line(task, i)
        if isinstance(task, Comfort):
            self.left_out.setdefault(
                f"tasks[{i}]", "the comfort task's neutral posture and weights"
            )
            neutral = ca.DM(task.measure.neutral)
            if not task.measure.effort:
                return task.measure.rows(self.body, self.q, neutral)
            return task.measure.rows(
                self.body, self.q, neutral, self.tau_act, self.comfort_strength
            )
        return task.residual(self.body, self._targets(task, i))

    def _targets(self, task: object, i: int) -> ca.SX:
        """A task's parameter vector (``Task.targets``) with its targets as inputs."""
        fixed = ca.DM(task.targets())
        if isinstance(task, Position | Gaze):
            return self._point(f"tasks[{i}].target_m", task.target)
        if isinstance(task, Plane):
            return self._point(f"tasks[{i}].point_m", task.point)
        if isinstance(task, JointReference):
            return ca.vertcat(
                *[
                    self._input(f"tasks[{i}].reference_deg.{d}", math.degrees(v), "deg", "target")
                    * (math.pi / 180.0)
                    for d, v in zip(task.dofs, task.reference, strict=True)
                ]
            )
        if isinstance(task, CentreOfMass):
            return self._centre_of_mass(task, i)
        if isinstance(task, Orientation):
            angles = self.problem.spec.tasks[i].target_rpy_deg
            roll, pitch, yaw = (
                self._input(f"tasks[{i}].target_rpy_deg[{k}]", a, "deg", "target")
                * (math.pi / 180.0)
                for k, a in enumerate(angles)
            )
            return ca.reshape(rpy_matrix(roll, pitch, yaw), 9, 1)  # column-major, as targets()
        if fixed.numel():
            self.left_out.setdefault(f"tasks[{i}]", f"the {task.name} task's target")
        return fixed

    def _line(self, task: Line, i: int) -> ca.SX:
        """A line task's residual [m] with its point and its elevation as inputs, and its
        azimuth for a body that does not move in one plane (a line turned out of that
        plane meets it in one point: the posture would jump there, with no derivative)."""
        spec = self.problem.spec.tasks[i]
        point = self._point(f"tasks[{i}].point_m", task.point)
        if spec.elevation_deg is None:
            self.left_out.setdefault(
                f"tasks[{i}].direction", "a direction vector (give elevation_deg instead)"
            )
            return task.residual(self.body, point)
        to_rad = math.pi / 180.0
        azimuth = spec.azimuth_deg or 0.0
        elevation = self._input(f"tasks[{i}].elevation_deg", spec.elevation_deg, "deg", "target")
        if self.problem.body.planar:
            self.left_out.setdefault(
                f"tasks[{i}].azimuth_deg",
                "the body moves in one plane, which a line turned out of it meets in one point",
            )
            turn = azimuth * to_rad
        else:
            turn = self._input(f"tasks[{i}].azimuth_deg", azimuth, "deg", "target") * to_rad
        direction = ca.vertcat(*direction_at(elevation * to_rad, turn))
        rows = normal_rows(direction, task.helper_axis())
        return rows @ (self.body.landmark(task.effector) - point)

    def _point(self, key: str, point: tuple[float, float, float]) -> ca.SX:
        return ca.vertcat(*[self._input(f"{key}[{k}]", point[k], "m", "target") for k in range(3)])

    def _centre_of_mass(self, task: CentreOfMass, i: int) -> ca.SX:
        """The target (the file's, or the centre of mass at the file's posture) in the task's
        axes, then the carried masses: those of the loads at their landmarks."""
        spec = self.problem.spec.tasks[i]
        carried_loads = [load for load in self.problem.loads if load.mass > 0]
        masses = [
            self._load_masses[self.problem.loads.index(load)]
            for load in carried_loads
            if task.carried
        ]
        axes = ["xyz".index(a) for a in task.axes]
        if spec.target_m is not None:
            target = self._point(f"tasks[{i}].target_m", tuple(spec.target_m))
        else:
            posture = ca.vertcat(
                *[
                    self._input(f"posture_deg.{d.name}", math.degrees(v), "deg", "posture")
                    * (math.pi / 180.0)
                    for d, v in zip(self.body.dofs, self.problem.posture, strict=True)
                ]
            )
            carried = [(load.at, m) for load, m in zip(carried_loads, masses, strict=False)]
            target = ca.substitute(self.body.com(carried), self.q, posture)
        return ca.vertcat(*[target[a] for a in axes], *masses)

    # -- outcomes -------------------------------------------------------------------------

    def _endurance(self, group: int, load_pct_mvc: ca.SX) -> ca.SX | None:
        """Group ``group``'s static endurance [s] at a load it is limited at, the law's
        coefficients as inputs (None: the law has no expression)."""
        region = self.problem.body.half_joints[group].region
        value: Callable[[Parameter], ca.SX | float] = self.record
        return self.problem.fatigue.endurance_expression(load_pct_mvc, region, value)

    def _load_pct_mvc(self) -> ca.SX:
        """Every half-joint's load [%MVC]: 100·max(±τa, 0)/st, positive group first."""
        rows = []
        for k, half in enumerate(self.problem.body.half_joints):
            torque = half.sign * self.tau_act[half.dof_index]
            rows.append(100.0 * ca.fmax(torque, 0.0) / self.strength[k])
        return ca.vertcat(*rows)


def _strength_key(problem: Problem, k: int, field: str = "strength_Nm") -> str:
    """The problem-file key ``field`` of half-joint ``k``'s strength."""
    half = problem.body.half_joints[k]
    if problem.spec.body.tree is None:
        return f"body.half_joints.{half.name}.{field}"
    side = "positive" if half.sign > 0 else "negative"
    return f"body.tree.dofs[{half.dof_index}].{side}.{field}"


def _file_group(problem: Problem, k: int) -> Any:
    """What the file sets for half-joint ``k`` (None: nothing)."""
    half = problem.body.half_joints[k]
    body = problem.spec.body
    if body.tree is None:
        return body.half_joints.get(half.name)
    dof = body.tree.dofs[half.dof_index]
    return dof.positive if half.sign > 0 else dof.negative


def _scale(problem: Problem, k: int) -> float:
    """Half-joint ``k``'s ``strength_scale`` in the file (1 when it gives none)."""
    group = _file_group(problem, k)
    scale = None if group is None else group.strength_scale
    return 1.0 if scale is None else scale


def _ratio(problem: Problem, k: int) -> float | None:
    """Half-joint ``k``'s ``strength_ratio`` in the file (None when it gives none)."""
    group = _file_group(problem, k)
    return None if group is None else group.strength_ratio


def _numbers(problem: Problem) -> np.ndarray:
    """The body's numbers (``shape.numbers``) with the problem's strengths."""
    return numbers(problem.body, problem.strength)
