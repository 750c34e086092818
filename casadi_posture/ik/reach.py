"""Whether a task's target lies out of its chain's reach, seeded starts within the joint
limits, and which joints a posture holds at a bound: the evidence that tells a target out
of reach from a local minimum of the IK."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.ik.result import ACHIEVED_TOLERANCE, ACTIVE_TOLERANCE
from casadi_posture.ik.tasks import Line, Plane, Position, Task


def random_starts(body: BodyModel, count: int, seed: int) -> np.ndarray:
    """``count`` postures [rad], one a row, each angle uniform within its joint range, from
    ``numpy.random.default_rng(seed)``: the same rows for the same body, count and seed,
    and the first rows of a longer draw."""
    rng = np.random.default_rng(seed)
    return rng.uniform(body.lower, body.upper, size=(count, body.n))


def chain(body: BodyModel, landmark: str) -> tuple[np.ndarray, float, float] | None:
    """The reach of ``landmark`` ignoring the joint limits: the centre of the first DOF of
    the chain that carries it (fixed in the world) [m], and the largest and the smallest
    distance from there a posture can put the landmark at [m] (the links' lengths summed,
    and the longest link less the others); None for a landmark fixed to the world."""
    point = body.landmarks[landmark]
    names = body.ancestors(point.dof)
    if not names:
        return None
    joints = [np.asarray(body.dofs[body.index[name]].origin, dtype=float) for name in names]
    points = np.array([*joints, np.asarray(point.position, dtype=float)])
    links = np.linalg.norm(np.diff(points, axis=0), axis=1)
    return points[0], float(links.sum()), max(0.0, float(2 * links.max() - links.sum()))


def beyond_reach(body: BodyModel, tasks: Sequence[Task]) -> str | None:
    """Why one of ``tasks`` (a priority level's) cannot be achieved by any posture, by its
    chain's reach: an effector's point, line or plane farther from the chain's first joint
    than the links reach, or a point nearer than they fold (by more than the level's
    ``ACHIEVED_TOLERANCE``); None when no task can be shown out of reach so."""
    for task in tasks:
        if not isinstance(task, Position | Line | Plane):
            continue
        reach = chain(body, task.effector)
        if reach is None:
            continue
        root, longest, shortest = reach
        distance, what = _distance(task, root)
        start = body.dofs[body.index[body.ancestors(body.landmarks[task.effector].dof)[0]]].name
        if distance > longest + ACHIEVED_TOLERANCE:
            return (
                f"{task.name}'s {what} is {distance:.3f} m from {start}'s centre, beyond "
                f"the {longest:.3f} m its chain reaches"
            )
        if isinstance(task, Position) and distance < shortest - ACHIEVED_TOLERANCE:
            return (
                f"{task.name}'s {what} is {distance:.3f} m from {start}'s centre, nearer "
                f"than the {shortest:.3f} m its chain folds to"
            )
    return None


def _distance(task: Position | Line | Plane, root: np.ndarray) -> tuple[float, str]:
    """The distance [m] from ``root`` to the task's point, line or plane, and its name."""
    if isinstance(task, Position):
        return float(np.linalg.norm(np.asarray(task.target) - root)), "target"
    offset = root - np.asarray(task.point, dtype=float)
    if isinstance(task, Line):
        direction = np.asarray(task.direction, dtype=float)
        direction = direction / np.linalg.norm(direction)
        return float(np.linalg.norm(offset - (offset @ direction) * direction)), "line"
    normal = np.asarray(task.normal, dtype=float)
    return abs(float(offset @ normal)) / float(np.linalg.norm(normal)), "plane"


def at_bounds(body: BodyModel, q: np.ndarray) -> list[str]:
    """Each DOF that ``q`` [rad] holds at a joint limit, as 'name at its lower (upper)
    limit, X°'."""
    out = []
    for i, dof in enumerate(body.dofs):
        for side, bound in (("lower", dof.lower), ("upper", dof.upper)):
            if abs(q[i] - bound) <= ACTIVE_TOLERANCE:
                out.append(f"{dof.name} at its {side} limit, {math.degrees(bound):g}°")
    return out
