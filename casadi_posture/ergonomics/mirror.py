"""Mirror symmetry about the body's sagittal plane (the world's x–z plane, y = 0).

A body is mirrored by swapping its ``_r`` and ``_l`` names; the built-in bodies keep the
anatomical sign of an angle on both sides, so a mirror-symmetric posture has equal angles
on paired DOFs and zero on the unpaired DOFs that turn out of the sagittal plane (lumbar
bending and rotation). A set of tasks and loads is symmetric when mirroring maps it onto
itself: points and forces (x, -y, z), moments (-x, y, -z) (an axial vector), rotations
M R M with M = diag(1, -1, 1).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np

from casadi_posture.biomech.comfort import ComfortMeasure
from casadi_posture.body.loads import Load
from casadi_posture.body.tree import BodyModel
from casadi_posture.ik.tasks import (
    CentreOfMass,
    Comfort,
    Feet,
    Gaze,
    JointReference,
    Line,
    Orientation,
    Plane,
    Position,
    Task,
)
from casadi_posture.spec.sides import mirror_name

#: Numbers that agree to this many decimals (m, N, N·m, rad, or a unit vector's
#: components) are taken as equal.
DECIMALS = 6
_M = np.diag([1.0, -1.0, 1.0])


def paired(body: BodyModel) -> list[tuple[int, int]]:
    """Index pairs (right, left) of the DOFs that mirror each other."""
    return [
        (i, body.index[other])
        for i, d in enumerate(body.dofs)
        if d.name.endswith("_r") and (other := mirror_name(d.name)) in body.index
    ]


def lateral(body: BodyModel) -> list[int]:
    """Unpaired DOFs that turn out of the sagittal plane (axis not along y at the zero
    posture): zero in a mirror-symmetric posture."""
    sided = {i for pair in paired(body) for i in pair}
    y = np.array([0.0, 1.0, 0.0])
    return [
        i
        for i, d in enumerate(body.dofs)
        if i not in sided and np.linalg.norm(np.cross(body.axis(d.name), y)) > 1e-9
    ]


def _numbers(values: Sequence[float] | np.ndarray) -> tuple[float, ...]:
    return tuple(
        float(v) for v in np.round(np.asarray(values, dtype=float).ravel(), DECIMALS) + 0.0
    )


def _point(v: Sequence[float], mirror: bool) -> tuple[float, ...]:
    return _numbers(_M @ np.asarray(v, dtype=float) if mirror else v)


def _axis(v: Sequence[float], mirror: bool) -> tuple[float, ...]:
    """A direction up to its sign (a line's or a plane's), as a unit vector."""
    u = np.asarray(v, dtype=float)
    u = (_M @ u if mirror else u) / np.linalg.norm(u)
    first = u[np.flatnonzero(np.abs(u) > 10.0**-DECIMALS)[0]]
    return _numbers(u if first > 0 else -u)


def _neutral(measure: ComfortMeasure, body: BodyModel, mirror: bool) -> tuple[float, ...]:
    if not mirror:
        return _numbers(measure.neutral)
    out = np.array(measure.neutral, dtype=float)
    for i, j in paired(body):
        out[i], out[j] = measure.neutral[j], measure.neutral[i]
    out[lateral(body)] *= -1.0
    return _numbers(out)


def _key(task: Task, body: BodyModel, mirror: bool) -> tuple | None:
    """What a task asks, mirrored or not, as comparable data (its name left out); None for
    a kind this module cannot mirror."""
    name = mirror_name if mirror else (lambda n: n)
    head = (type(task).__name__, task.priority)
    if isinstance(task, Position):
        return (*head, name(task.effector), _point(task.target, mirror))
    if isinstance(task, Line):
        # A line is its direction and its closest point to the origin.
        u = np.asarray(task.direction, dtype=float) / np.linalg.norm(task.direction)
        p = np.asarray(task.point, dtype=float)
        return (*head, name(task.effector), _point(p - (p @ u) * u, mirror), _axis(u, mirror))
    if isinstance(task, Plane):
        n = np.asarray(task.normal, dtype=float) / np.linalg.norm(task.normal)
        offset = float(np.asarray(task.point, dtype=float) @ n)
        return (*head, name(task.effector), _point(offset * n, mirror), _axis(n, mirror))
    if isinstance(task, Orientation):
        r = np.asarray(task.rotation, dtype=float).reshape(3, 3)
        return (*head, name(task.segment), name(task.dof), _numbers(_M @ r @ _M if mirror else r))
    if isinstance(task, CentreOfMass):
        carried = tuple(sorted((name(at), round(kg, DECIMALS)) for at, kg in task.carried))
        return (*head, task.axes, _point(task.target, mirror), carried)
    if isinstance(task, Gaze):
        return (
            *head,
            name(task.segment),
            name(task.dof),
            name(task.eye),
            _point(task.forward, mirror),
            _point(task.target, mirror),
        )
    if isinstance(task, JointReference):
        flip = {body.dofs[i].name for i in lateral(body)} if mirror else set()
        pairs = sorted(
            (name(d), round(-v if d in flip else v, DECIMALS) + 0.0)
            for d, v in zip(task.dofs, task.reference, strict=True)
        )
        return (*head, tuple(pairs))
    if isinstance(task, Comfort):
        return (*head, task.measure.name, _neutral(task.measure, body, mirror))
    if isinstance(task, Feet):
        return head
    return None


def _load_key(load: Load, mirror: bool) -> tuple:
    name = mirror_name(load.at) if mirror else load.at
    moment = _numbers(-(_M @ np.asarray(load.moment)) if mirror else load.moment)
    return (name, round(load.mass, DECIMALS), _point(load.force, mirror), moment)


def symmetric(body: BodyModel, tasks: Sequence[Task], loads: Sequence[Load]) -> bool:
    """Whether mirroring maps the tasks and loads onto themselves (the body having sides and
    the problem tasks): a person would then hold them with a mirror-symmetric posture."""
    if not paired(body) or not tasks:
        return False
    keys = [_key(t, body, False) for t in tasks]
    mirrored = [_key(t, body, True) for t in tasks]
    if any(k is None for k in keys):
        return False
    loads_same = Counter(_load_key(ld, False) for ld in loads) == Counter(
        _load_key(ld, True) for ld in loads
    )
    return loads_same and Counter(keys) == Counter(mirrored)


def asymmetry(body: BodyModel, q: np.ndarray) -> tuple[float, str | None]:
    """The largest departure [rad] of posture ``q`` from mirror symmetry: a paired DOF's
    difference from its mirror, or an out-of-plane unpaired DOF's angle; and its DOF (the
    right one of a pair)."""
    worst, where = 0.0, None
    for i, j in paired(body):
        if abs(q[i] - q[j]) > worst:
            worst, where = abs(float(q[i] - q[j])), body.dofs[i].name
    for i in lateral(body):
        if abs(q[i]) > worst:
            worst, where = abs(float(q[i])), body.dofs[i].name
    return worst, where
