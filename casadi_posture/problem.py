"""Problem files: read, validate and resolve into a body with its loads, tasks and settings."""

from __future__ import annotations

import hashlib
import math
import tomllib
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ValidationError

from casadi_posture.biomech.comfort import comfort_measure
from casadi_posture.biomech.endurance import endurance_model
from casadi_posture.biomech.fatigue import FatigueModel, fatigue_model
from casadi_posture.biomech.passive import (
    ExponentialPassive,
    NoPassive,
    PassiveTorque,
    ReshapedPassive,
    limit_torque,
)
from casadi_posture.biomech.strength import (
    ConstantStrength,
    Strength,
    TabulatedStrength,
    default_strength,
    elbow_flexion,
    known_groups,
)
from casadi_posture.biomech.torques import TorqueModel
from casadi_posture.body.anthropometry import SegmentInertia, segment_inertia
from casadi_posture.body.file_tree import body_from_tree, check_tree
from casadi_posture.body.loads import Load
from casadi_posture.body.models import MODELS
from casadi_posture.body.tree import BodyModel
from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter, data_name
from casadi_posture.errors import MISSING, ProblemError
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.tasks import Task as IKTask
from casadi_posture.ik.tasks import tasks_from_specs
from casadi_posture.spec.overrides import MAX_NESTING, apply, changes, check_nesting
from casadi_posture.spec.schema import (
    ComfortTask,
    ComTask,
    ExponentialPassiveSpec,
    FeetTask,
    GazeTask,
    LimitTorquePassiveSpec,
    OrientationTask,
    PostureTask,
    ProblemSpec,
    Task,
    TreeDofSpec,
    TreeHalfJointSpec,
    TreeSpec,
    passive_model_tag,
)
from casadi_posture.spec.slips import problem_notes, radians_note


@dataclass(frozen=True)
class Problem:
    """A validated problem: the body (``tree`` as a problem file writes it, built-in models
    included), its torque model inputs, the posture [rad], settings and the fatigue model
    (stateless: one state per simulation); ``data`` is what it was read
    from (the file's tables with the ``overrides`` applied), ``text_sha256`` the SHA-256 of
    the file's text when it came from one, ``notes`` the slips it may hold (spec/slips.py)."""

    path: Path
    spec: ProblemSpec
    body: BodyModel
    passive: dict[str, PassiveTorque]
    strength: dict[str, Strength]
    loads: tuple[Load, ...]
    posture: np.ndarray
    parameters: tuple[Parameter, ...]
    fatigue: FatigueModel
    tree: TreeSpec
    data: dict[str, Any] = field(default_factory=dict)
    overrides: dict[str, Any] = field(default_factory=dict)
    text_sha256: str | None = None
    notes: tuple[str, ...] = ()

    def __repr__(self) -> str:
        changed = f", overrides={self.overrides}" if self.overrides else ""
        return (
            f"Problem({str(self.path)!r}, {self.body.name}, {self.body.n} DOF, "
            f"{len(self.loads)} loads, {len(self.spec.tasks)} tasks{changed})"
        )

    @property
    def tasks(self) -> list[Task]:
        return list(self.spec.tasks)

    @property
    def heading(self) -> str:
        """The file's ``title`` for titles and headers, saying what the overrides changed
        (``--set``, a what-if case) since the title was written: ``My shelf: a 4 kg box ...
        (changed: loads[0].mass_kg = 6)``; a ``title`` set by an override stands as given;
        empty without a title."""
        title = self.spec.title
        if not title or not self.overrides or "title" in self.overrides:
            return title
        return f"{title} (changed: {changes(self.overrides, most=MOST_CHANGES)})"

    def hierarchy(self) -> TaskHierarchy:
        """The problem's tasks grouped into priority levels (built once per call)."""
        if not self.spec.tasks:
            raise ProblemError(self.path, "tasks", MISSING, "at least one task to solve")
        return TaskHierarchy(self.body, self.task_objects())

    def task_objects(self) -> list[IKTask]:
        """The problem's tasks as IK task objects (none for a problem without tasks)."""
        return tasks_from_specs(
            self.spec.tasks, self.body, self.loads, self.posture, self.passive, self.strength
        )

    def torque_model(self) -> TorqueModel:
        """The compiled torque functions of this problem (build once, evaluate many)."""
        return TorqueModel(self.body, self.loads, self.passive, self.strength)

    def with_overrides(self, overrides: Mapping[str, Any]) -> Problem:
        """The same problem with more dotted keys set, as ``load_problem``'s ``overrides``
        (segment lengths measured on a recorded subject, say)."""
        changed = problem_from_data(self.data, self.path, overrides)
        merged = {**self.overrides, **overrides}
        return replace(changed, overrides=merged, text_sha256=self.text_sha256)

    def with_posture(self, degrees: dict[str, float], key: str = "--posture") -> Problem:
        """The same problem at another posture, given per DOF in degrees."""
        q = self.posture.copy()
        for name, angle in degrees.items():
            q[_dof_index(self.body, name, key, self.path)] = math.radians(
                _degrees(angle, key, name, self.path)
            )
        _check_posture(self.body, q, key, self.path)
        note = radians_note(degrees, key, self.path)
        return replace(self, posture=q, notes=self.notes if note is None else (*self.notes, note))


def read_problem_text(path: str | Path) -> str:
    """The text of a problem file; a missing or unreadable file raises ``ProblemError``."""
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ProblemError(path, None, None, "the file does not exist") from None
    except IsADirectoryError:
        raise ProblemError(path, None, None, "a problem file, got a directory") from None
    except (OSError, UnicodeDecodeError) as error:
        raise ProblemError(path, None, None, f"a readable UTF-8 file ({error})") from None


def load_problem(
    path: str | Path, overrides: Mapping[str, Any] | None = None, *, text: str | None = None
) -> Problem:
    """Read, validate and resolve a problem file; any fault raises ``ProblemError``.

    ``overrides`` sets dotted keys before validation, e.g. ``{"fatigue.strategy":
    "passive", "loads[0].mass_kg": 5.0}`` (command-line options, what-if grids).
    ``text``, when given, is the file's content (a batch worker that has no copy of
    the file); ``path`` then only names it in messages.
    """
    path = Path(path)
    text = read_problem_text(path) if text is None else text
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ProblemError(path, None, None, f"valid TOML ({error})") from None
    except RecursionError:
        raise ProblemError(
            path, None, None, f"valid TOML nested at most {MAX_NESTING} deep"
        ) from None
    problem = problem_from_data(raw, path, overrides)
    return replace(problem, text_sha256=text_sha256(text))


def text_sha256(text: str) -> str:
    """The SHA-256 of a problem file's text (UTF-8), as manifests record it."""
    return hashlib.sha256(text.encode()).hexdigest()


def problem_from_data(
    data: Mapping[str, Any], name: str | Path = "<data>", overrides: Mapping[str, Any] | None = None
) -> Problem:
    """Validate and resolve a problem given as plain data (what a problem file holds, as a
    dict); ``name`` names it in messages; ``overrides`` as for ``load_problem``."""
    path = Path(name)
    check_nesting(data, path)
    raw = apply(dict(data), overrides or {}, path)
    check_nesting(raw, path)  # the overrides' values too
    try:
        spec = ProblemSpec.model_validate(raw)
    except ValidationError as error:
        raise _problem_error(path, error, raw) from None
    try:
        problem = resolve(spec, path)
    except ProblemError as error:
        if error.file is None:
            raise ProblemError(path, error.key, error.value, error.expected) from None
        raise
    notes = problem_notes(spec, path)
    return replace(problem, data=raw, overrides=dict(overrides or {}), notes=notes)


#: Overrides a title names (``Problem.heading``); the page's subtitle and the manifest
#: hold them all.
MOST_CHANGES = 4


def resolve(spec: ProblemSpec, path: Path) -> Problem:
    """Build the body model and its loads, strengths and passive torques from a spec: the
    file's own ``body.tree``, or the tree of a built-in ``body.model`` with its overrides."""
    records: list[Parameter] = [parameters.load("constants")["constants.gravity"]]
    if spec.body.tree is not None:
        tree = spec.body.tree
        check_tree(tree, path)
        where = [f"body.tree.dofs[{i}]" for i in range(len(tree.dofs))]
        records += [
            Parameter(f"joints.{d.name}.range", d.range_deg, "deg", f"{path} {w}.range_deg", "user")
            for d, w in zip(tree.dofs, where, strict=True)
        ]
    else:
        tree, built = _builtin_tree(spec, path)
        where = [f"body.dofs.{d.name}" for d in tree.dofs]
        records += built
    body = body_from_tree(tree, records[0].value)

    passive: dict[str, PassiveTorque] = {}
    strength: dict[str, Strength] = {}
    for dof, key in zip(tree.dofs, where, strict=True):
        passive[dof.name], passive_records = _passive(dof, key, path)
        records += passive_records
        for side in ("positive", "negative"):
            group = getattr(dof, side)
            group_key = (
                f"{key}.{side}" if spec.body.tree is not None else f"body.half_joints.{group.name}"
            )
            strength[group.name], record = _strength(
                group, group_key, body, body.index[dof.name], spec, path
            )
            records.append(record)

    loads = tuple(_load(body, spec, i, path) for i in range(len(spec.loads)))
    _check_tasks(body, spec, path)
    regions = [h.region for h in body.half_joints]
    endurance = endurance_model(spec.fatigue.endurance or default_endurance(body))
    fatigue = fatigue_model(
        spec.fatigue.recovery_law,
        regions=regions,
        endurance=endurance,
        recovery_threshold_pct_mvc=spec.fatigue.load_threshold_pct_mvc,
    )
    records += endurance.parameters(regions) + fatigue.parameters()

    q = np.zeros(body.n)
    for name, angle in spec.posture_deg.items():
        q[_dof_index(body, name, f"posture_deg.{name}", path)] = math.radians(angle)
    _check_posture(body, q, "posture_deg", path)
    unique: dict[str, Parameter] = {}
    for record in records:
        unique.setdefault(record.name, record)
    records = tuple(unique.values())
    return Problem(path, spec, body, passive, strength, loads, q, records, fatigue, tree)


def _builtin_tree(spec: ProblemSpec, path: Path) -> tuple[TreeSpec, list[Parameter]]:
    """The tree of the built-in model ``body.model`` scaled to the file's body, with the
    file's overrides of DOFs, segments and half-joints merged in, and the records of its
    segments and ranges."""
    body_spec = spec.body
    if body_spec.model not in MODELS:
        raise ProblemError(path, "body.model", body_spec.model, f"one of {sorted(MODELS)}")
    recipe = MODELS[body_spec.model]
    records: list[Parameter] = []
    _unknown(path, "body.segments", body_spec.segments, recipe.segments)
    segments = {}
    for name in recipe.segments:
        inertia = segment_inertia(
            name, sex=body_spec.sex, stature=body_spec.stature_m, body_mass=body_spec.mass_kg
        )
        segments[name] = _override_segment(inertia, body_spec.segments.get(name), path)
        records += segments[name].parameters

    _unknown(path, "body.dofs", body_spec.dofs, recipe.dofs)
    table = parameters.load("joints")
    ranges: dict[str, tuple[float, float]] = {}
    for name in recipe.dofs:
        override = body_spec.dofs.get(name)
        shipped = f"joints.{data_name(name)}.range"
        lo, hi = (
            replace(table[f"{shipped}.{end}"], name=f"joints.{name}.range.{end}")
            for end in ("lower", "upper")
        )
        if override is not None and override.range_deg is not None:
            where = f"{path} body.dofs.{name}.range_deg"
            lo = lo.overridden(override.range_deg[0], where)
            hi = hi.overridden(override.range_deg[1], where)
        ranges[name] = (lo.value, hi.value)
        records += [lo, hi]
    if body_spec.hip_height_m is not None and recipe.name != "upper_body":
        expected = "no hip_height_m (it places the fixed pelvis of model 'upper_body' only)"
        raise ProblemError(path, "body.hip_height_m", body_spec.hip_height_m, expected)
    tree, derived = recipe.build(segments, ranges, body_spec)
    rebuilt = {record.name for record in derived}  # the builder's own values win
    records = [record for record in records if record.name not in rebuilt] + derived

    groups = [side.name for d in tree.dofs for side in (d.positive, d.negative)]
    _unknown(path, "body.half_joints", body_spec.half_joints, groups)
    dofs = []
    for dof in tree.dofs:
        changes: dict[str, Any] = {}
        override = body_spec.dofs.get(dof.name)
        if override is not None:
            changes = {"passive": override.passive, "reshape": override.reshape}
        for side in ("positive", "negative"):
            group = getattr(dof, side)
            given = body_spec.half_joints.get(group.name)
            if given is not None:
                changes[side] = group.model_copy(
                    update={
                        "strength_Nm": given.strength_Nm,
                        "strength_curve": given.strength_curve,
                        "strength_scale": given.strength_scale,
                        "strength_ratio": given.strength_ratio,
                    }
                )
        dofs.append(dof.model_copy(update=changes))
    return tree.model_copy(update={"dofs": dofs}), records


def _override_segment(inertia: SegmentInertia, override: Any, path: Path) -> SegmentInertia:
    if override is None:
        return inertia
    where = f"{path} body.segments.{inertia.name}"
    changes = {}
    if override.mass_kg is not None:
        changes["mass"] = override.mass_kg
    if override.length_m is not None:
        changes["length"] = override.length_m
    if override.com_fraction is not None:
        changes["com_fraction"] = override.com_fraction
    updated = replace(inertia, **changes)
    records = []
    for record in inertia.parameters:
        field = record.name.rsplit(".", 1)[-1]
        new = {
            "mass": updated.mass,
            "length": updated.length,
            "com_distance": updated.com_distance,
        }.get(field)
        changed = new is not None and not math.isclose(new, record.value, rel_tol=1e-12)
        records.append(record.overridden(round(new, 6), where) if changed else record)
    return replace(updated, parameters=tuple(records))


#: The passive model of a DOF whose file says nothing of it and whose shipped data name no
#: default (``joints.<dof>.passive.default``), e.g. a DOF of the file's own.
DEFAULT_PASSIVE_MODEL = "limit_torque"
_EXPONENTIAL_KEYS = ("k1", "k2", "q1", "k3", "k4", "q2")
_EXPONENTIAL_UNITS = ("N·m", "1/rad", "deg", "N·m", "1/rad", "deg")


def _passive(dof: TreeDofSpec, key: str, path: Path) -> tuple[PassiveTorque, list[Parameter]]:
    """The passive torque of ``dof`` and its parameter records: the model the file names,
    else the shipped default of a DOF of that name (side suffix stripped), else
    ``limit_torque``; reshaped near the limits of the DOF's range if asked. A shipped set
    (``anderson_1999``, ``gymnast_fit``) is taken by name from ``joints.toml``.

    The limit-torque convention is anchored at the anatomical range of motion of a DOF the
    package has data for, not at the file's ``range_deg`` (extending the range lets the joint
    into the tissue's steep rise past its limit); a DOF of the file's own at its range."""
    override, name = dof.passive, dof.name
    where = f"{path} {key}.passive"
    table = parameters.load("joints")
    shipped = f"joints.{data_name(name)}.passive."
    default = table.get(shipped + "default")
    if override is not None:
        chosen = Parameter(f"joints.{name}.passive.model", override.model, "", where, "user")
    elif default is not None:
        chosen = replace(default, name=f"joints.{name}.passive.model", unit="")
    else:
        source = "the default passive model"
        chosen = Parameter(
            f"joints.{name}.passive.model", DEFAULT_PASSIVE_MODEL, "", source, "estimate"
        )
    model_name = chosen.value
    if model_name == "none":
        return NoPassive(), [chosen]
    if model_name == "limit_torque":
        model, records = _limit_torque(dof, override, where, key, path)
        records = [chosen, *records]
    elif isinstance(override, ExponentialPassiveSpec):
        given = [getattr(override, f) for f in ExponentialPassiveSpec.model_fields if f != "model"]
        records = [
            chosen,
            *(
                Parameter(f"joints.{name}.passive.{k}", v, unit, where, "user")
                for k, v, unit in zip(_EXPONENTIAL_KEYS, given, _EXPONENTIAL_UNITS, strict=True)
            ),
        ]
        model = _exponential(records[1:])
    else:
        prefix = f"{shipped}{model_name}."
        if prefix + "k1" not in table:
            fitted = sorted({p.split(".")[1] for p in table if f".{model_name}." in p})
            expected = f"a model other than {model_name} (fitted only for {fitted})"
            raise ProblemError(path, f"{key}.passive.model", model_name, expected)
        records = [
            replace(table[prefix + k], name=f"joints.{name}.passive.{k}") for k in _EXPONENTIAL_KEYS
        ]
        model = _exponential(records)
        records = [chosen, *records]
    if dof.reshape is not None:
        shape = dof.reshape
        lower, upper = (math.radians(v) for v in dof.range_deg)
        model = ReshapedPassive(
            model,
            lower,
            upper,
            math.radians(shape.width_deg),
            shape.slope_Nm_per_rad,
            shape.step_Nm,
        )
        records.append(
            Parameter(
                f"joints.{name}.passive.reshape",
                shape.model_dump(),
                "deg, N·m/rad, N·m",
                f"{path} {key}.reshape",
                "user",
            )
        )
    return model, records


def _exponential(records: list[Parameter]) -> ExponentialPassive:
    """The double exponential of six records k1, k2, q1, k3, k4, q2 (angles in deg, or rad
    where a record's unit says so: the shipped anderson_1999 sets keep their source's)."""
    k1, k2, q1, k3, k4, q2 = (
        math.radians(r.value) if r.unit == "deg" else r.value for r in records
    )
    return ExponentialPassive(k1, k2, q1, k3, k4, q2)


def _limit_torque(
    dof: TreeDofSpec,
    override: LimitTorquePassiveSpec | None,
    where: str,
    key: str,
    path: Path,
) -> tuple[ExponentialPassive, list[Parameter]]:
    """The limit-torque convention of ``dof`` with the file's values over the shipped ones
    (a shipped DOF without limit-torque numbers of its own takes those of ``any_dof`` at its
    shipped range)."""
    table, name, base = parameters.load("joints"), dof.name, data_name(dof.name)
    shipped = f"joints.{base}.range.lower" in table
    own = f"joints.{base}.passive.limit_torque.limit" in table
    prefix = f"joints.{base if own else 'any_dof'}.passive.limit_torque."
    limit, decade = table[prefix + "limit"], table[prefix + "decade"]
    if shipped:
        lower, upper = table[f"joints.{base}.range.lower"], table[f"joints.{base}.range.upper"]
    else:
        source = f"{path} {key}.range_deg"
        lower, upper = (
            Parameter(f"joints.{name}.passive.{end}", value, "deg", source, "user")
            for end, value in zip(("lower", "upper"), dof.range_deg, strict=True)
        )
    if override is not None:
        if override.limit_Nm is not None:
            limit = limit.overridden(override.limit_Nm, where)
        if override.decade is not None:
            decade = decade.overridden(override.decade, where)
        if override.lower_deg is not None:
            lower = lower.overridden(override.lower_deg, where)
        if override.upper_deg is not None:
            upper = upper.overridden(override.upper_deg, where)
    if not lower.value < upper.value:
        raise ProblemError(
            path, f"{key}.passive", [lower.value, upper.value], "lower_deg < upper_deg"
        )
    model = limit_torque(
        math.radians(lower.value), math.radians(upper.value), limit.value, decade.value
    )
    limit = replace(limit, name=f"joints.{name}.passive.limit_torque.limit")
    decade = replace(decade, name=f"joints.{name}.passive.limit_torque.decade")
    return model, [limit, decade, *_derived(name, model)]


def _derived(dof: str, model: ExponentialPassive) -> list[Parameter]:
    """The double exponential's coefficients that the limit-torque convention gives."""
    values = (
        (model.k1, "N·m"),
        (model.k2, "1/rad"),
        (math.degrees(model.q1), "deg"),
        (model.k3, "N·m"),
        (model.k4, "1/rad"),
        (math.degrees(model.q2), "deg"),
    )
    return [
        Parameter(
            f"joints.{dof}.passive.{key}",
            round(value, 6),
            unit,
            "derived: the limit torque at the anatomical limits, rate ln 10/(decade·range)",
            "estimate",
        )
        for key, (value, unit) in zip(_EXPONENTIAL_KEYS, values, strict=True)
    ]


def _strength(
    group: TreeHalfJointSpec,
    key: str,
    body: BodyModel,
    dof_index: int,
    spec: ProblemSpec,
    path: Path,
) -> tuple[Strength, Parameter]:
    """The strength of a muscle group (of the DOF ``dof_index`` in q): the file's value,
    curve or ratio to the body's elbow flexion, else the shipped default of a group of that
    name, times the file's ``strength_scale`` if it gives one."""
    where = f"{path} {key}"
    name = group.name
    if group.strength_Nm is not None:
        value = group.strength_Nm
        return ConstantStrength(value), Parameter(f"strength.{name}", value, "N·m", where, "user")
    if group.strength_curve is not None:
        curve = group.strength_curve
        index = _dof_index(body, curve.dof, f"{key}.strength_curve.dof", path)
        model = TabulatedStrength(
            index, tuple(math.radians(a) for a in curve.angle_deg), tuple(curve.strength_Nm)
        )
        table = list(zip(curve.angle_deg, curve.strength_Nm, strict=True))
        return model, Parameter(f"strength.{name}", table, "[deg, N·m]", where, "user")
    b = spec.body
    if group.strength_ratio is not None:
        elbow, words = elbow_flexion(b.sex, b.stature_m, b.mass_kg, b.age_years)
        value = elbow * group.strength_ratio
        source = f"{where}.strength_ratio = {group.strength_ratio:g} × {words} = {value:.2f} N·m"
        return ConstantStrength(value), Parameter(
            f"strength.{name}", round(value, 4), "N·m", source, "user"
        )
    if data_name(name) not in known_groups():
        expected = (
            "a strength_Nm, strength_curve or strength_ratio (shipped defaults only for "
            f"{known_groups()})"
        )
        raise ProblemError(path, f"{key}.strength_Nm", MISSING, expected)
    model, record = default_strength(
        name,
        sex=b.sex,
        stature=b.stature_m,
        body_mass=b.mass_kg,
        age=b.age_years,
        dof_index=dof_index,
    )
    if group.strength_scale is None:
        return model, record
    scale = group.strength_scale
    scaled = replace(model, value=model.value * scale)
    shown = (
        round(record.value * scale, 4)
        if isinstance(record.value, float)
        else [(a, round(v * scale, 4)) for a, v in record.value]
    )
    source = f"{path} {key}.strength_scale = {scale:g} × the default ({record.source})"
    return scaled, replace(record, value=shown, source=source, status="user", evidence="")


def _load(body: BodyModel, spec: ProblemSpec, i: int, path: Path) -> Load:
    item = spec.loads[i]
    if item.at not in body.landmarks:
        raise ProblemError(path, f"loads[{i}].at", item.at, f"one of {sorted(body.landmarks)}")
    return Load(item.name, item.at, item.mass_kg, tuple(item.force_N), tuple(item.moment_Nm))


def _check_tasks(body: BodyModel, spec: ProblemSpec, path: Path) -> None:
    names: set[str] = set()
    for i, task in enumerate(spec.tasks):
        key = f"tasks[{i}]"
        if task.name in names:
            raise ProblemError(path, f"{key}.name", task.name, "a name no other task has")
        names.add(task.name)
        if isinstance(task, OrientationTask | GazeTask):
            segments = [s.name for s in body.segments]
            if task.segment not in segments:
                raise ProblemError(path, f"{key}.segment", task.segment, f"one of {segments}")
            if isinstance(task, GazeTask) and task.eye not in body.landmarks:
                raise ProblemError(path, f"{key}.eye", task.eye, f"one of {sorted(body.landmarks)}")
        elif isinstance(task, PostureTask):
            for dof in task.reference_deg:
                _dof_index(body, dof, f"{key}.reference_deg.{dof}", path)
        elif isinstance(task, ComfortTask):
            _check_comfort(body, spec, i, path)
        elif isinstance(task, FeetTask) and not any(f.dof for f in body.feet):
            raise ProblemError(path, f"{key}.kind", "feet", "a body standing on two feet")
        elif (
            not isinstance(task, ComTask | FeetTask | ComfortTask)
            and task.effector not in body.landmarks
        ):
            raise ProblemError(
                path, f"{key}.effector", task.effector, f"one of {sorted(body.landmarks)}"
            )


def _check_comfort(body: BodyModel, spec: ProblemSpec, i: int, path: Path) -> None:
    """A comfort task is alone at the lowest priority (it is a criterion over what every task
    leaves free, not a task beside others) and its measure resolves on this body."""
    task = spec.tasks[i]
    lowest = max(t.priority for t in spec.tasks)
    others = [t.name for t in spec.tasks if t.priority == task.priority and t is not task]
    if task.priority != lowest or others:
        expected = (
            f"a priority below every other task's, alone at its level (lowest other: {lowest})"
            if task.priority != lowest
            else f"a level of its own (shared with {others})"
        )
        raise ProblemError(path, f"tasks[{i}].priority", task.priority, expected)
    try:
        comfort_measure(
            body,
            task.measure,
            weights=task.weights,
            joint_weights=task.joint_weights,
            neutral_deg=task.neutral_deg,
            key=f"tasks[{i}]",
        )
    except ProblemError as error:
        raise ProblemError(path, error.key, error.value, error.expected) from None


def _degrees(angle: Any, key: str, name: str, path: Path) -> float:
    """An angle given for DOF ``name``, as a finite number of degrees."""
    if isinstance(angle, bool) or not isinstance(angle, int | float) or not math.isfinite(angle):
        raise ProblemError(path, f"{key}.{name}", angle, "a finite number of degrees")
    return float(angle)


def default_endurance(body: BodyModel) -> str:
    """The endurance model of a file that names none: the paper's single curve (Manenica)
    on a body moving in one plane, as the paper's scenarios; Frey-Law & Avin's curves per
    joint region on a 3-D body, whose trunk, leg and wrist groups the paper's one curve
    was never fitted to (at 19 %MVC it gives the ankle plantarflexors 6.4 min against the
    meta-analysis' 17.7; docs/endurance.md)."""
    return "manenica" if body.planar else "frey_law_avin"


def _dof_index(body: BodyModel, name: str, key: str, path: Path) -> int:
    if name not in body.index:
        raise ProblemError(path, key, name, f"a DOF of {body.name}: one of {body.dof_names}")
    return body.index[name]


def _check_posture(body: BodyModel, q: np.ndarray, key: str, path: Path) -> None:
    for i, dof in enumerate(body.dofs):
        if not dof.lower - 1e-12 <= q[i] <= dof.upper + 1e-12:
            raise ProblemError(
                path,
                f"{key}.{dof.name}",
                round(math.degrees(q[i]), 6),
                f"an angle within the range [{math.degrees(dof.lower):g}, "
                f"{math.degrees(dof.upper):g}] deg",
            )


def _unknown(path: Path, key: str, given: dict[str, Any], known: Any) -> None:
    for name in given:
        if name not in known:
            raise ProblemError(path, f"{key}.{name}", name, f"one of {sorted(known)}")


def _problem_error(path: Path, error: ValidationError, raw: dict[str, Any]) -> ProblemError:
    """The first pydantic error as one line naming the key, the value and what was expected."""
    errors = error.errors(include_url=False)
    first = errors[0]
    loc = list(first["loc"])
    key = _key(loc, raw)
    message = first["msg"].removeprefix("Value error, ").removeprefix("Input should be ")
    if first["type"] == "extra_forbidden":
        allowed = _allowed_keys(loc[:-1])
        message = f"a known key: one of {allowed}" if allowed else "no such key"
    elif first["type"] == "missing":
        message = "this key to be given"
    elif first["type"] == "union_tag_invalid":
        message = f"one of {first['ctx']['expected_tags']}"
        first = {**first, "input": first["ctx"]["tag"]}
    elif first["type"] in ("too_short", "too_long"):
        ctx = first.get("ctx", {})
        n = ctx.get("min_length") if first["type"] == "too_short" else ctx.get("max_length")
        message = f"{'at least' if first['type'] == 'too_short' else 'at most'} {n} items"
    elif first["type"] in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        message += _unit_of(key)
    elif first["type"] in ("model_type", "model_attributes_type", "dict_type"):
        message = "a table of keys (TOML {...} or [section]), not a single value"
    elif first["type"] == "finite_number":
        message = "a finite number" + (f" [{_unit_of(key).strip()}]" if _unit_of(key) else "")
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    value = first.get("input", MISSING) if first["type"] != "missing" else MISSING
    if isinstance(value, dict):
        value = MISSING
    return ProblemError(path, key, value, message + more)


#: Units named by the suffix of a key, for range messages and axis labels.
KEY_UNITS = {
    "_m": " m (metres: a position in cm or mm is a unit slip)",
    "_deg": " deg",
    "_kg": " kg",
    "_N": " N",
    "_Nm": " N·m",
    "_s": " s",
    "_pct_mvc": " %MVC",
    "_per_rad": " 1/rad",
}


def _unit_of(key: str) -> str:
    """The unit a key's name carries (``tasks[0].point_m[1]`` -> metres), or ''."""
    name = key.rsplit(".", 1)[-1].split("[", 1)[0]
    return next((unit for suffix, unit in KEY_UNITS.items() if name.endswith(suffix)), "")


def _key(loc: list[Any], raw: dict[str, Any]) -> str:
    """Dotted key of a pydantic location, with list indices and without union tags."""
    text, node = "", raw
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
            node = node[part] if isinstance(node, list) and part < len(node) else None
            continue
        if (
            isinstance(node, dict)
            and part not in node
            and part in (node.get("kind"), passive_model_tag(node))
        ):
            continue
        text += f".{part}" if text else str(part)
        node = node.get(part) if isinstance(node, dict) else None
    return text


def _allowed_keys(loc: list[Any]) -> list[str]:
    """The keys the table at pydantic location ``loc`` accepts."""
    annotation: Any = ProblemSpec
    for part in loc:
        annotation = _step(annotation, part)
        if annotation is None:
            return []
    models = [leaf for leaf in _leaves(annotation) if _is_model(leaf)]
    return sorted(models[0].model_fields) if len(models) == 1 else []


def _step(annotation: Any, part: Any) -> Any:
    """The annotation one location step below ``annotation`` (field, item, value or union tag)."""
    leaves = _leaves(annotation)
    for leaf in leaves:
        origin = typing.get_origin(leaf)
        if _is_model(leaf) and part in leaf.model_fields:
            return leaf.model_fields[part].annotation
        if origin is list and isinstance(part, int):
            return typing.get_args(leaf)[0]
        if origin is dict and isinstance(part, str):
            return typing.get_args(leaf)[1]
    for leaf in leaves:
        if _is_model(leaf) and any(
            part in typing.get_args(leaf.model_fields[tag].annotation)
            for tag in ("kind", "model")
            if tag in leaf.model_fields
        ):
            return leaf
    return None


def _leaves(annotation: Any) -> list[Any]:
    """The alternatives of a union, unwrapping ``Annotated`` and ``Optional``."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _leaves(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        return [leaf for arg in typing.get_args(annotation) for leaf in _leaves(arg)]
    return [annotation]


def _is_model(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)
