"""The free quantities of a design: ``--free KEY=LO:HI`` parsed, each key checked (a task
target coordinate of the file, in metres, within its bounds), tied keys, and each key's
index in the hierarchy's target vector."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from casadi_posture.errors import MISSING, CasadiPostureError, ProblemError
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.spec.overrides import parse_key
from casadi_posture.spec.schema import ComTask, GazeTask, LineTask, PlaneTask, PositionTask

_TARGET_FIELDS = {
    PositionTask: "target_m",
    GazeTask: "target_m",
    ComTask: "target_m",
    LineTask: "point_m",
    PlaneTask: "point_m",
}
_EXPECTED_KEY = (
    "a task's target coordinate: tasks[i].point_m[k] (line, plane) or tasks[i].target_m[k] "
    "(position, gaze, com with a target), k = 0, 1, 2 for x, y, z"
)


@dataclass(frozen=True)
class Free:
    """One design variable: the problem-file ``keys`` it sets (several keys tied together
    share one value), its bounds and its value in the file [m], and the indices of those
    keys in the hierarchy's target vector ``p``."""

    keys: tuple[str, ...]
    lower_m: float
    upper_m: float
    start_m: float
    indices: tuple[int, ...]

    @property
    def name(self) -> str:
        return ",".join(self.keys)


def parse_free(items: Sequence[str], path: Any = None) -> dict[str, tuple[float, float]]:
    """``--free KEY=LO:HI`` options (``KEY1,KEY2=LO:HI`` ties keys to one value) as
    {keys: (LO, HI)} [m]; a malformed option, a bound that is not a finite number, LO ≥ HI
    or a key given twice is a ``ProblemError``."""
    out: dict[str, tuple[float, float]] = {}
    seen: set[str] = set()
    for item in items:
        keys, sep, bounds = item.partition("=")
        lo_text, colon, hi_text = bounds.partition(":")
        if not sep or not keys or not colon:
            expected = "KEY=LO:HI in metres, such as 'tasks[2].target_m[2]=1.0:1.6'"
            raise ProblemError(path, "--free", item, expected)
        try:
            lo, hi = float(lo_text), float(hi_text)
        except ValueError:
            lo = hi = math.nan
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ProblemError(
                path, f"--free {keys}", bounds, "LO:HI, two finite numbers of metres"
            )
        if not lo < hi:
            raise ProblemError(path, f"--free {keys}", bounds, "LO < HI [m]")
        for key in keys.split(","):
            if key in seen:
                raise ProblemError(path, "--free", key, "each key freed once")
            seen.add(key)
        out[keys] = (lo, hi)
    return out


def free_quantities(
    problem: Problem, hierarchy: TaskHierarchy, free: Mapping[str, tuple[float, float]]
) -> list[Free]:
    """The design variables of ``free`` ({KEY or KEY1,KEY2: (LO, HI)} [m]) on ``problem``:
    each key checked (a task target coordinate of the file, within the bounds, in metres)
    and mapped to its index in ``hierarchy.p``; tied keys must share their file value."""
    path = problem.path
    if not free:
        raise ProblemError(path, "--free", MISSING, "at least one KEY=LO:HI to design")
    out, seen = [], set()
    for names, (lo, hi) in free.items():
        keys = tuple(names.split(","))
        for key in keys:
            if key in seen:
                raise ProblemError(path, "--free", key, "each key freed once")
            seen.add(key)
        values = [_value(problem, key) for key in keys]
        if len(set(values)) > 1:
            shown = ", ".join(f"{k} = {v:g}" for k, v in zip(keys, values, strict=True))
            expected = "tied keys that share one value in the file (one shelf, one height)"
            raise ProblemError(path, f"--free {names}", shown, expected)
        for key in keys:
            for bound in (lo, hi):
                _check_bound(problem, key, bound)
        start = values[0]
        if not lo <= start <= hi:
            expected = f"bounds that hold the file's value {start:g} m"
            raise ProblemError(path, f"--free {names}", f"{lo:g}:{hi:g}", expected)
        indices = tuple(_target_index(problem, hierarchy, key) for key in keys)
        out.append(Free(keys, float(lo), float(hi), start, indices))
    return out


def _value(problem: Problem, key: str) -> float:
    """The file's value [m] of task target coordinate ``key``; anything else is refused."""
    path = problem.path
    try:
        parts = parse_key(key)
    except ProblemError:
        raise ProblemError(path, "--free", key, _EXPECTED_KEY) from None
    if parts and parts[0] == "loads":
        expected = (
            "a task target: a load hangs on a body landmark (loads[i].at), so its position "
            "is not a free quantity; free the target of the task that holds it"
        )
        raise ProblemError(path, f"--free {key}", MISSING, expected)
    shape = [type(p) for p in parts]
    if shape != [str, int, str, int] or parts[0] != "tasks":
        raise ProblemError(path, "--free", key, _EXPECTED_KEY)
    _, i, field, k = parts
    tasks = problem.spec.tasks
    if not 0 <= i < len(tasks):
        raise ProblemError(path, f"--free {key}", i, f"a task index below {len(tasks)}")
    task = tasks[i]
    wanted = _TARGET_FIELDS.get(type(task))
    if wanted is None or field != wanted:
        what = f"{wanted}[k]" if wanted else "nothing: it has no target point"
        expected = f"{_EXPECTED_KEY}; task {task.name!r} ({task.kind}) frees {what}"
        raise ProblemError(path, f"--free {key}", field, expected)
    if not 0 <= k < 3:
        raise ProblemError(path, f"--free {key}", k, "a coordinate index 0, 1 or 2 (x, y, z)")
    point = getattr(task, field)
    if point is None:
        expected = "a com task with a target_m (without one the target follows the posture)"
        raise ProblemError(path, f"--free {key}", MISSING, expected)
    if isinstance(task, ComTask) and "xyz"[k] not in task.axes:
        expected = f"an axis the com task constrains ({task.axes})"
        raise ProblemError(path, f"--free {key}", "xyz"[k], expected)
    return float(point[k])


def _check_bound(problem: Problem, key: str, value: float) -> None:
    """A bound is validated as the file's value would be (metres, the unit-slip check)."""
    try:
        problem_from_data(problem.data, problem.path, {key: value})
    except ProblemError as error:
        raise ProblemError(problem.path, f"--free {key}", value, error.expected) from None


def _target_index(problem: Problem, hierarchy: TaskHierarchy, key: str) -> int:
    """Index of ``key``'s coordinate in ``hierarchy.p``: the task's offset (the sizes of
    the ``targets()`` before it, level by level) plus the coordinate's place among its
    targets (position, line, plane, gaze: x, y, z; com: its axes, masses after them)."""
    _, i, _, k = parse_key(key)
    spec = problem.spec.tasks[i]
    offset = 0
    for level in hierarchy.blocks:
        for task, _rows in level:
            if task.name == spec.name:
                place = spec.axes.index("xyz"[k]) if isinstance(spec, ComTask) else k
                index = offset + place
                if not math.isclose(hierarchy.targets[index], _value(problem, key)):
                    raise CasadiPostureError(f"{key}: the task's targets are not laid out as read")
                return index
            offset += task.targets().size
    raise CasadiPostureError(f"{key}: task {spec.name!r} is not in the hierarchy")


def as_overrides(quantities: Sequence[Free], d: Sequence[float]) -> dict[str, float]:
    """Design values [m] as problem-file overrides {key: value}."""
    return {k: float(v) for f, v in zip(quantities, d, strict=True) for k in f.keys}
