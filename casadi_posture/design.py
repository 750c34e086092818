"""Workplace design by gradients: the task's target coordinates (a shelf's height, a line's
position) chosen within bounds to maximise the task's static endurance or the share of a
population capable of it, or to minimise the low-back compression, by one NLP over the
posture and the design together (docs/design.md).

Variables: the posture q [rad] within the joint limits, the design d [m] within its bounds
and the epigraph variable t. Constraints: every priority level the IK achieves at the start
design is kept as an equality e_k(q, p(d)) = 0 (the others, typically the lowest posture
task, are dropped: the person takes whichever posture is best). Objective, maximise t with

- ``endurance``: ``log E_g(max(L_g, T_0)) ≥ t`` for every half-joint g, with
  ``L_g = 100·σ_g·τa_j(q)/st_g(q)`` [%MVC] (σ = +1 for the positive group, −1 for the
  negative) and ``E_g`` the fatigue model's endurance [s]; clamped at the load threshold
  T_0, a group at or below it never binds ("unlimited below T_0"); and ``L_g ≤ 100 %MVC``;
- ``capable-male`` / ``capable-female``: ``(μ_g − max(τ_g, 0))/s_g ≥ t`` with μ_g, s_g the
  population strength's mean and SD [N·m] of that sex (biomech/capability.py): Φ is
  monotone, so the largest smallest z-score is the largest share capable;
- ``compression``: ``−C_m(q) ≥ t`` [N] for each muscle m of the L5/S1 compression
  C = −F·e_z + max(M_s/E, −M_s/A) of biomech/low_back.py (its CasADi expressions):
  C_e = −F·e_z + M_s/E (erector spinae), C_a = −F·e_z − M_s/A (rectus abdominis), so that
  the largest t is −C without the kink of the max at M_s = 0; the lumbar bending and
  rotation are held at the start's (the model leaves out the moments they would hide the
  load in).

The NLP starts from the IK's posture at the start design, which is feasible, and is built
once per problem structure (the targets, loads and bounds are its parameters). The answer
is checked by re-solving the IK with the problem file's solver at the design.
"""

from __future__ import annotations

import hashlib
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from casadi_posture import static
from casadi_posture.biomech.capability import SEXES, Sex, capability
from casadi_posture.biomech.endurance import numeric
from casadi_posture.biomech.low_back import (
    LUMBAR,
    MODEL,
    OUTPUTS,
    has_lumbar_joint,
    low_back_expressions,
    moment_arms,
)
from casadi_posture.biomech.low_back import limits as compression_limits
from casadi_posture.body.loads import pack
from casadi_posture.errors import MISSING, CasadiPostureError, ProblemError
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.result import ACHIEVED_TOLERANCE
from casadi_posture.problem import Problem, problem_from_data
from casadi_posture.spec.overrides import parse_key
from casadi_posture.spec.schema import ComTask, GazeTask, LineTask, PlaneTask, PositionTask

OBJECTIVES = ("endurance", "capable-male", "capable-female", "compression")

#: The JSON key of a compression score [N].
COMPRESSION_UNIT = "compression_N"

#: The low-back outputs the compression objective's measures are made of.
_COMPRESSION_TERMS = ("compression", "sagittal_moment", "muscle_force")

#: A design value within this of a bound [m] is reported at that bound.
BOUND_TOLERANCE_M = 1e-6

#: The re-solved IK agrees with the NLP when its endurance or compression is within this
#: fraction of the NLP's [-], or its share capable within this many percentage points [%].
CHECK_RELATIVE = 0.01
CHECK_SHARE_PCT = 0.5

#: A load at most this far above T_0 [%MVC] counts as clamped (not limiting) at the optimum.
CLAMP_MARGIN_PCT_MVC = 1e-3

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
    or a key given twice is a :class:`ProblemError`."""
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


@dataclass(frozen=True)
class Score:
    """The objective at one design and posture: the static endurance [min] (``inf``:
    unlimited) or the share capable [%], with its limiting group, the group's region and
    load [%MVC]; or the L5/S1 compression [N] (no group: None)."""

    value: float
    group: str | None
    region: str | None
    load_pct_mvc: float | None

    def to_dict(self, unit: str) -> dict[str, Any]:
        if unit == COMPRESSION_UNIT:
            limit = compression_limits()
            return {
                unit: self.value,
                "above_niosh_design_limit": self.value > limit["design"],
                "above_niosh_upper_limit": self.value > limit["upper"],
            }
        return {
            unit: self.value,
            "limiting_group": self.group,
            "limiting_region": self.region,
            "limiting_load_pct_mvc": self.load_pct_mvc,
        }


def score(answer: static.StaticAnswer, objective: str) -> Score:
    """The objective of a static answer: the limiting group's endurance [min] (``inf`` when
    no group tires), the task's share capable [%] for the objective's sex, or the L5/S1
    compression [N] (``LowBackModel.evaluate`` at the answer's posture)."""
    problem, body = answer.problem, answer.problem.body
    if objective == "compression":
        assert answer.low_back is not None, "design() refuses a body without a lumbar joint"
        return Score(answer.low_back.compression, None, None, None)
    if objective == "endurance":
        group = answer.limiting
        if group is None:
            return Score(math.inf, None, None, None)
        k = [h.name for h in body.half_joints].index(group.name)
        return Score(
            group.endurance_min, group.name, body.half_joints[k].region, group.load_pct_mvc
        )
    sex = _sex(objective)
    result = capability(
        static.population_strength(problem, answer.torques.strength),
        answer.torques.half_joint_torque,
    )
    weakest = result.weakest(sex)
    if weakest is None:
        return Score(result.share(sex), None, None, None)
    k = [h.name for h in body.half_joints].index(weakest.name)
    load = float(answer.torques.load_pct_mvc[k])
    return Score(result.share(sex), weakest.name, body.half_joints[k].region, load)


def _sex(objective: str) -> Sex:
    sex = objective.removeprefix("capable-")
    assert sex in SEXES
    return sex  # type: ignore[return-value]


@dataclass(frozen=True)
class _Nlp:
    """The compiled design NLP of one problem structure and its sizes."""

    solver: ca.Function
    objective: ca.Function
    equalities: int
    redundant: int
    groups: int
    limits: int

    def constraint_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """lbg, ubg: the kept levels = 0, the epigraph rows ≥ 0, the load limits ≤ 0."""
        zeros, inf = np.zeros, np.full
        lbg = np.concatenate(
            [zeros(self.equalities), zeros(self.groups), inf(self.limits, -np.inf)]
        )
        ubg = np.concatenate([zeros(self.equalities), inf(self.groups, np.inf), zeros(self.limits)])
        return lbg, ubg


_cache = threading.local()

#: Design NLPs a thread keeps (one per problem structure, kept levels and free keys).
CACHED_STRUCTURES = 4

#: IPOPT's iteration limit for the design NLP.
MAX_ITERATIONS = 1000


def design_nlp(
    problem: Problem,
    hierarchy: TaskHierarchy,
    kept: Sequence[int],
    free: Sequence[Free],
    objective: str,
    start: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> _Nlp:
    """The design NLP (module docstring) with x = [q, d, t] and parameters [targets, loads],
    built once per structure in this thread (keyed by the SHA-256 of its functions).

    The kept levels' rows are taken in priority order, and a row whose gradient in (q, d)
    at the ``start`` (q [rad], d [m], parameters) is a combination of those before it is
    left out: an achieved posture task on the joints the feet already fix, a dot on the
    line it lies on, would make IPOPT's equality Jacobian rank-deficient (more equalities
    than variables). The others imply it near the start (constant rank); the residual of
    every kept level is checked at the answer."""
    body, torques = problem.body, problem.torque_model()
    q, d, t = body.q, ca.SX.sym("d", len(free)), ca.SX.sym("t")
    base = ca.SX.sym("targets", hierarchy.p.numel())
    p = ca.SX(base)
    for j, quantity in enumerate(free):
        for index in quantity.indices:
            p[index] = d[j]
    residual = ca.substitute(ca.vertcat(*[hierarchy.residuals[k] for k in kept]), hierarchy.p, p)
    qd = ca.vertcat(q, d)
    params = ca.vertcat(base, torques.p)
    gradient = ca.Function("gradient", [qd, params], [ca.jacobian(residual, qd)])
    q0, d0, p0 = start
    rows = independent_rows(np.asarray(gradient(np.concatenate([q0, d0]), p0)))
    equalities = residual[rows] if rows else ca.SX(0, 1)
    measures, limits = _measures(problem, torques, objective)
    x = ca.vertcat(q, d, t)
    g = ca.vertcat(equalities, measures - t, limits)
    nlp = {"x": x, "p": params, "f": -t, "g": g}
    key = hashlib.sha256(
        ca.Function("design", [x, params], [-t, g]).serialize().encode()
    ).hexdigest()
    if not hasattr(_cache, "nlps"):
        _cache.nlps = OrderedDict()
    nlps: OrderedDict = _cache.nlps
    if key not in nlps:
        ipopt = {
            "print_level": 0,
            "sb": "yes",
            "max_iter": MAX_ITERATIONS,
            "tol": 1e-8,
            # limited-memory for a row per group (on the standing shelf the exact Hessian was
            # slower and stopped lower), exact for the compression's two rows (the
            # limited-memory one ran out of iterations at fixed shelf heights)
            "hessian_approximation": "exact" if objective == "compression" else "limited-memory",
        }
        options = {"print_time": False, "error_on_fail": False, "ipopt": ipopt}
        nlps[key] = ca.nlpsol("design", "ipopt", nlp, options)
        while len(nlps) > CACHED_STRUCTURES:
            nlps.popitem(last=False)
    nlps.move_to_end(key)
    value = ca.Function("measure", [q, params], [ca.mmin(measures)])
    return _Nlp(
        nlps[key], value, len(rows), residual.numel() - len(rows), measures.numel(), limits.numel()
    )


def independent_rows(jacobian: np.ndarray, tolerance: float = 1e-9) -> list[int]:
    """Indices of the rows of ``jacobian`` that are not combinations of the rows before them
    (Gram-Schmidt, twice, with a relative ``tolerance``); a zero row is never kept."""
    basis: list[np.ndarray] = []
    rows = []
    for r, row in enumerate(jacobian):
        v = row.astype(float)
        for _ in range(2):
            for b in basis:
                v = v - b.dot(v) * b
        if np.linalg.norm(v) > tolerance * max(1.0, float(np.linalg.norm(row))):
            basis.append(v / np.linalg.norm(v))
            rows.append(r)
    return rows


def _measures(problem: Problem, torques: Any, objective: str) -> tuple[ca.SX, ca.SX]:
    """The epigraph's measures — per half-joint the log-endurance [log s] or z-score [-],
    or per back muscle −compression [N] — and the extra inequalities ``L_g − 100 ≤ 0`` [%MVC]
    (endurance only), all in ``body.q`` and the load vector ``torques.p``."""
    body = problem.body
    if objective == "compression":
        extensor, flexor = moment_arms()
        back = low_back_expressions(body, problem.loads, torques.p, extensor, flexor)
        compression, moment, muscle = (back[OUTPUTS.index(k)] for k in _COMPRESSION_TERMS)
        axial = compression - muscle  # −F·e_z [N], smooth
        # muscle = max(M, 0)/E + max(−M, 0)/A = max(M/E, −M/A): a row per muscle, smooth
        rows = ca.vertcat(axial + moment / extensor, axial - moment / flexor)
        return -rows, ca.SX(0, 1)
    active = [torques.tau_act[h.dof_index] * h.sign for h in body.half_joints]
    strength = [torques.strength[k] for k in range(len(body.half_joints))]
    if objective == "endurance":
        threshold = _threshold(problem)
        load = [100.0 * a / s for a, s in zip(active, strength, strict=True)]
        measure = [
            ca.log(problem.fatigue.endurance_expression(ca.fmax(L, threshold), h.region, numeric))
            for L, h in zip(load, body.half_joints, strict=True)
        ]
        return ca.vertcat(*measure), ca.vertcat(*load) - 100.0
    sex = _sex(objective)
    # population_strength() is affine in the strength it is given (a group the file sets takes the
    # problem's strength as its mean, SD = CV × mean; the others are constant): its value at
    # strengths 0 and 1 gives each group's mean and SD as expressions of st_g(q).
    zero = static.population_strength(problem, np.zeros(len(strength)))
    one = static.population_strength(problem, np.ones(len(strength)))
    measure = []
    for a, s, g0, g1 in zip(active, strength, zero, one, strict=True):
        mean = g0.mean[sex] + (g1.mean[sex] - g0.mean[sex]) * s
        sd = g0.sd[sex] + (g1.sd[sex] - g0.sd[sex]) * s
        measure.append((mean - ca.fmax(a, 0.0)) / sd)
    return ca.vertcat(*measure), ca.SX(0, 1)


def _threshold(problem: Problem) -> float:
    """T_0 [%MVC] of the endurance objective, refused where the clamp cannot work: the 3CC
    law (no expression), T_0 ≤ 0, or an endurance not finite at T_0."""
    settings = problem.fatigue.settings()
    law = settings["recovery_law"]
    probe = ca.SX.sym("load")
    regions = dict.fromkeys(h.region for h in problem.body.half_joints)
    if any(problem.fatigue.endurance_expression(probe, r, numeric) is None for r in regions):
        expected = (
            "threshold or continuous for --objective endurance (the 3cc_r endurance is found "
            "by time stepping: no gradient); --objective capable-male or capable-female "
            "works with any law"
        )
        raise ProblemError(problem.path, "fatigue.recovery_law", law, expected)
    threshold = float(settings["load_threshold_pct_mvc"])
    if not threshold > 0:
        expected = (
            "T_0 > 0 %MVC for --objective endurance (a group that carries nothing has no "
            "finite endurance to clamp at T_0)"
        )
        raise ProblemError(problem.path, "fatigue.load_threshold_pct_mvc", threshold, expected)
    for region in regions:
        seconds = float(problem.fatigue.endurance_expression(ca.DM(threshold), region, numeric))
        if not (math.isfinite(seconds) and seconds > 0):
            expected = (
                f"a law whose endurance at T_0 is finite (region {region}: {seconds} s); "
                "use --objective capable-male or capable-female"
            )
            raise ProblemError(problem.path, "fatigue.recovery_law", law, expected)
    return threshold


@dataclass(frozen=True)
class Design:
    """A design and its checks.

    ``free`` the design variables; ``best_m`` their values at the optimum [m]; ``start``,
    ``best`` and ``check`` the objective at the start (IK), at the NLP's answer and by the
    IK re-solved at the best design (a compression by ``LowBackModel.evaluate``);
    ``kept``/``dropped`` the priority levels kept as equalities or dropped;
    ``status``/``success``/``iterations``/``wall_time_s`` IPOPT's; ``notes`` say what to
    know, ``flags`` why the answer cannot be used as it is.
    """

    problem: Problem
    objective: str
    free: tuple[Free, ...]
    best_m: tuple[float, ...]
    start: Score
    best: Score
    check: Score
    start_answer: static.StaticAnswer
    best_answer: static.StaticAnswer
    check_answer: static.StaticAnswer
    kept: tuple[str, ...]
    dropped: tuple[str, ...]
    status: str
    success: bool
    iterations: int
    wall_time_s: float
    kept_residual: float
    posture_gap_deg: float
    agrees: bool
    notes: tuple[str, ...]
    flags: tuple[str, ...]

    @property
    def unit(self) -> str:
        """The JSON key of the objective's value, with its unit."""
        units = {"endurance": "endurance_min", "compression": COMPRESSION_UNIT}
        return units.get(self.objective, "capable_pct")

    @property
    def gain_unit(self) -> str:
        """The unit of :attr:`gain`."""
        units = {"endurance": "min", "compression": "N"}
        return units.get(self.objective, "percentage points")

    @property
    def gain(self) -> float:
        """The answer: the IK re-solved at the best design − start [min or percentage
        points] (``inf``: the re-solve is unlimited), or start − re-solved for the
        compression [N] (its reduction). What a person at the design would do, as far as the
        IK predicts it; :attr:`nlp_gain` is the NLP's own."""
        return _gain(self.start, self.check, self.objective)

    @property
    def nlp_gain(self) -> float:
        """The gain of the NLP's posture at the best design over the start (as :attr:`gain`)."""
        return _gain(self.start, self.best, self.objective)

    @property
    def ratio(self) -> float | None:
        """re-solved / start [-] (``inf``: from a finite to an unlimited endurance; below 1:
        a compression reduced; None from a start of 0, where no ratio exists)."""
        if math.isinf(self.check.value) and math.isinf(self.start.value):
            return 1.0
        return self.check.value / self.start.value if self.start.value > 0 else None

    def at_bound(self, j: int) -> str | None:
        """'lower' or 'upper' when design variable j ends at that bound, else None."""
        f, v = self.free[j], self.best_m[j]
        if v <= f.lower_m + BOUND_TOLERANCE_M:
            return "lower"
        if v >= f.upper_m - BOUND_TOLERANCE_M:
            return "upper"
        return None

    def overrides(self) -> dict[str, float]:
        """The best design as problem-file overrides {key: value [m]}."""
        return _overrides(self.free, self.best_m)

    def to_dict(self) -> dict[str, Any]:
        """Everything the command prints, as plain data (units in the key names; an
        endurance of None is unlimited)."""
        unit = self.unit
        return {
            "problem": str(self.problem.path),
            "objective": self.objective,
            "free": [
                {
                    "keys": list(f.keys),
                    "lower_m": f.lower_m,
                    "upper_m": f.upper_m,
                    "start_m": f.start_m,
                    "best_m": self.best_m[j],
                    "at_bound": self.at_bound(j),
                }
                for j, f in enumerate(self.free)
            ],
            "levels_kept": list(self.kept),
            "levels_dropped": list(self.dropped),
            "start": self.start.to_dict(unit),
            "best": self.best.to_dict(unit),
            "gain": {
                "absolute": self.gain,
                "unit": self.gain_unit,
                "direction": "reduction: start − re-solved"
                if self.objective == "compression"
                else "increase: re-solved − start",
                "ratio": self.ratio,
                "of": "the IK re-solved at the best design",
                "nlp_absolute": self.nlp_gain,
                "note": "the re-solve is unlimited (null: no finite gain)"
                if math.isinf(self.gain)
                else None,
            },
            "ipopt": {
                "status": self.status,
                "success": self.success,
                "iterations": self.iterations,
                "wall_time_s": self.wall_time_s,
            },
            "kept_levels_residual": self.kept_residual,
            "check": {
                **self.check.to_dict(unit),
                "agrees": self.agrees,
                "tolerance": (
                    f"{CHECK_SHARE_PCT:g} percentage points"
                    if self.objective.startswith("capable-")
                    else f"{100 * CHECK_RELATIVE:g} % of the NLP's {self.objective}"
                ),
                "posture_gap_deg": self.posture_gap_deg,
                "solver": self.check_answer.ik.solver if self.check_answer.ik else None,
            },
            **self._low_back(),
            "notes": list(self.notes),
            "flags": list(self.flags),
        }

    def _low_back(self) -> dict[str, Any]:
        """The compression objective's model and NIOSH limits [N] (nothing for the others)."""
        if self.objective != "compression":
            return {}
        return {"low_back": {"model": MODEL, "niosh_limits_N": compression_limits()}}


@dataclass(frozen=True)
class _Start:
    """What the design starts from: the IK's answer at the file's design, its objective and
    the priority levels kept as equalities and dropped."""

    problem: Problem
    objective: str
    free: tuple[Free, ...]
    answer: static.StaticAnswer
    score: Score
    kept: tuple[int, ...]


def spread(count: int, dims: int) -> np.ndarray:
    """``count − 1`` points of the unit box [0, 1]^dims, one row each: the Hammersley set
    of ``count`` points without its origin. The first coordinate is evenly spaced (i/count:
    one free key gets evenly spaced starts); the others are the radical inverses of i in
    the primes 2, 3, 5, ..., so that the points fill the box instead of its diagonal."""
    primes: list[int] = []
    candidate = 2
    while len(primes) < dims - 1:
        if all(candidate % q for q in primes):
            primes.append(candidate)
        candidate += 1

    def radical_inverse(i: int, base: int) -> float:
        value, scale = 0.0, 1.0 / base
        while i:
            i, digit = divmod(i, base)
            value += digit * scale
            scale /= base
        return value

    rows = [[i / count, *(radical_inverse(i, b) for b in primes)] for i in range(1, count)]
    return np.array(rows, dtype=float).reshape(count - 1, dims)


def design(
    problem: Problem,
    free: Mapping[str, tuple[float, float]],
    objective: str = "endurance",
    keep_levels: int | None = None,
    starts: int = 1,
) -> Design:
    """Choose the ``free`` quantities ({KEY or KEY1,KEY2: (LO, HI)} [m]) to maximise
    ``objective`` (one of :data:`OBJECTIVES`; the compression is minimised, with the lumbar
    bending and rotation held at the start's) by the design NLP, and check the answer by
    re-solving the IK with the file's solver at the best design. The levels the IK achieves
    at the start are kept as equalities, only the first ``keep_levels`` of them if given
    (a posture task the start happens to achieve would otherwise fix the posture).
    ``starts`` > 1 also starts the NLP from the IK at ``starts − 1`` designs spread over
    the bounds (:func:`spread`; a local method: the best answer is kept)."""
    if starts < 1:
        raise ProblemError(problem.path, "--starts", starts, "a number of starts ≥ 1")
    if objective not in OBJECTIVES:
        raise ProblemError(problem.path, "--objective", objective, f"one of {list(OBJECTIVES)}")
    hierarchy = problem.hierarchy()
    if keep_levels is not None and not 1 <= keep_levels <= hierarchy.depth:
        expected = f"a number of levels from 1 to {hierarchy.depth}"
        raise ProblemError(problem.path, "--keep-levels", keep_levels, expected)
    quantities = tuple(free_quantities(problem, hierarchy, free))
    if objective == "endurance":
        _threshold(problem)
    if objective == "compression" and not has_lumbar_joint(problem.body):
        expected = (
            f"a body with a lumbar joint (a {LUMBAR[0]} DOF) for the L5/S1 compression; "
            f"body {problem.body.name!r} has none: use endurance or capable-male/female"
        )
        raise ProblemError(problem.path, "--objective", objective, expected)
    answer = static.solve(problem)
    if not answer.reached:
        raise CasadiPostureError(
            f"{problem.path}: level 1 is not achieved at the start design "
            f"({answer.flags[0] if answer.flags else 'no detail'}); a design "
            "starts from a feasible posture"
        )
    depth = hierarchy.depth if keep_levels is None else keep_levels
    kept = tuple(k for k, lv in enumerate(answer.levels) if lv.achieved and k < depth)
    start = _Start(problem, objective, quantities, answer, score(answer, objective), kept)
    notes = [static.SCHEDULE_NOTE] if problem.spec.schedule is not None else []
    dropped = [lv for lv in answer.levels if lv.level - 1 not in kept]
    if dropped:
        reasons = {True: "above --keep-levels", False: "not achieved at the start"}
        why = ", ".join(f"{lv.level} ({lv.tasks}, {reasons[lv.achieved]})" for lv in dropped)
        notes.append(
            f"levels dropped: {why}; the person takes whichever posture is best for the objective"
        )
    q0 = answer.torques.q
    d0 = np.array([f.start_m for f in quantities])
    if objective == "endurance" and math.isinf(start.score.value):
        notes.append(
            "every group is at or below T_0 at the start: the task is unlimited already, "
            "nothing to maximise (the start is the design)"
        )
        return _finish(start, d0, q0, _Run("not run (unlimited at the start)"), notes, [])
    params = np.concatenate([hierarchy.targets, pack(problem.loads)])
    nlp = design_nlp(problem, hierarchy, kept, quantities, objective, (q0, d0, params))
    if nlp.redundant:
        notes.append(
            f"{nlp.redundant} rows of the kept levels repeat others at the start (their "
            "gradients are combinations of higher rows) and were left out of the NLP; every "
            "kept level's residual is checked at the answer"
        )
    if nlp.equalities >= problem.body.n + len(quantities):
        notes.append(
            f"the kept levels fix the posture and the design ({nlp.equalities} independent "
            f"equations on {problem.body.n} joints and {len(quantities)} design values): "
            "nothing to choose; drop a level with --keep-levels to let the body move"
        )
        return _finish(start, d0, q0, _Run("not run (no freedom)"), notes, [])
    lower = np.array([f.lower_m for f in quantities])
    upper = np.array([f.upper_m for f in quantities])
    points = [(q0, d0)]
    for fraction in spread(starts, len(quantities)):
        d_i = lower + (upper - lower) * fraction
        at = problem_from_data(problem.data, problem.path, _overrides(quantities, d_i))
        other = static.solve(at)
        if all(other.levels[k].achieved for k in kept):
            points.append((other.torques.q, d_i))
    if starts > 1:
        notes.append(
            f"{len(points)} starts (the file's design and {len(points) - 1} of {starts - 1} "
            "designs spread over the bounds whose IK keeps the task); the best answer is "
            "reported"
        )
    body = problem.body
    joints_lower, joints_upper = body.lower, body.upper
    if objective == "compression":
        held = [body.index[name] for name in LUMBAR[1:] if name in body.index]
        joints_lower[held] = joints_upper[held] = q0[held]
        shown = ", ".join(
            f"{body.dof_names[i]} {round(math.degrees(q0[i]), 1) + 0.0:g}°" for i in held
        )
        notes.append(
            f"trunk held as at the start ({shown}): the sagittal model leaves out the lateral "
            "and twisting moments, and the NLP would bend and twist the trunk to hide the "
            "load from it"
        )
    lbx = np.concatenate([joints_lower, lower, [-np.inf]])
    ubx = np.concatenate([joints_upper, upper, [np.inf]])
    lbg, ubg = nlp.constraint_bounds()
    best: tuple[float, _Run, np.ndarray] | None = None
    for q_i, d_i in points:
        t0 = float(nlp.objective(q_i, params))
        began = time.perf_counter()
        out = nlp.solver(
            x0=np.concatenate([q_i, d_i, [t0]]), p=params, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg
        )
        wall = time.perf_counter() - began
        stats = nlp.solver.stats()
        run = _Run(str(stats["return_status"]), bool(stats["success"]), stats["iter_count"], wall)
        x = np.asarray(out["x"]).ravel()
        rank = (run.success, float(x[-1]))
        if best is None or rank > (best[1].success, best[0]):
            best = (float(x[-1]), run, x)
    assert best is not None
    _, run, x = best
    q = np.clip(x[: body.n], body.lower, body.upper)
    d = np.clip(x[body.n : body.n + len(quantities)], lower, upper)
    flags = [] if run.success else [f"IPOPT failed: {run.status}"]
    return _finish(start, d, q, run, notes, flags)


def _overrides(quantities: Sequence[Free], d: Sequence[float]) -> dict[str, float]:
    """Design values [m] as problem-file overrides {key: value}."""
    return {k: float(v) for f, v in zip(quantities, d, strict=True) for k in f.keys}


@dataclass(frozen=True)
class _Run:
    """IPOPT's outcome: its status word, success, iterations and wall time [s]."""

    status: str
    success: bool = True
    iterations: int = 0
    wall_time_s: float = 0.0


def _finish(
    start: _Start, d: np.ndarray, q: np.ndarray, run: _Run, notes: list[str], flags: list[str]
) -> Design:
    """The best design's answer at the NLP's posture ``q`` [rad] and values ``d`` [m], the
    re-solve check and their notes."""
    problem, objective, kept = start.problem, start.objective, start.kept
    at_best = problem_from_data(problem.data, problem.path, _overrides(start.free, d))
    best_answer = static.at_posture(at_best, q)
    best = score(best_answer, objective)
    residuals = at_best.hierarchy().residual_norms(q)
    kept_residual = max((float(residuals[k]) for k in kept), default=0.0)
    if kept_residual > ACHIEVED_TOLERANCE:
        flags.append(
            f"the NLP's posture leaves a kept level at {kept_residual:.3g} "
            f"(> {ACHIEVED_TOLERANCE:g}): the design does not keep the task"
        )
    if _better(start.score, best, objective) and run.success:
        flags.append("the NLP ended worse than the start's objective (a local method left it)")
    check_answer = static.solve(at_best)
    check = score(check_answer, objective)
    gap = float(np.degrees(np.max(np.abs(check_answer.torques.q - q))))
    agrees = _agree(best, check, objective)
    lost = [lv.level for lv in check_answer.levels if lv.level - 1 in kept and not lv.achieved]
    if lost:
        flags.append(f"the re-solved IK does not achieve kept level(s) {lost} at the design")
    if not agrees:
        gain = "reduction" if objective == "compression" else "gain"
        flags.append(
            f"the re-solved IK ({check_answer.ik.solver if check_answer.ik else '-'}) gives "
            f"{_show(check.value, objective)} where the NLP gives {_show(best.value, objective)}: "
            f"it settles the posture its own way (largest joint difference {gap:.1f} deg), "
            "with the dropped levels pulling it, while the NLP takes the posture best for the "
            f"objective among those that keep the task; the {gain} is the re-solve's, and the "
            "NLP's posture is not what the IK predicts a person does at the design"
        )
    if objective == "endurance" and best.load_pct_mvc is not None and math.isfinite(best.value):
        threshold = float(problem.fatigue.settings()["load_threshold_pct_mvc"])
        if best.load_pct_mvc <= threshold + CLAMP_MARGIN_PCT_MVC:
            flags.append(
                "the limiting group sits at T_0 at the optimum: the clamp, not the group's "
                "endurance, bounded the objective"
            )
    levels = start.answer.levels
    return Design(
        problem=problem,
        objective=objective,
        free=start.free,
        best_m=tuple(float(v) for v in d),
        start=start.score,
        best=best,
        check=check,
        start_answer=start.answer,
        best_answer=best_answer,
        check_answer=check_answer,
        kept=tuple(f"{levels[k].level}: {levels[k].tasks}" for k in kept),
        dropped=tuple(f"{lv.level}: {lv.tasks}" for lv in levels if lv.level - 1 not in kept),
        status=run.status,
        success=run.success,
        iterations=run.iterations,
        wall_time_s=run.wall_time_s,
        kept_residual=kept_residual,
        posture_gap_deg=gap,
        agrees=agrees,
        notes=tuple(notes),
        flags=tuple(flags + list(best_answer.flags)),
    )


def _gain(start: Score, end: Score, objective: str) -> float:
    """end − start [min or percentage points], start − end for the compression [N]; 0
    between two unlimited endurances."""
    if math.isinf(end.value) and math.isinf(start.value):
        return 0.0
    if objective == "compression":
        return start.value - end.value
    return end.value - start.value


def _better(a: Score, b: Score, objective: str) -> bool:
    """Whether score ``a`` is better than ``b`` beyond the check tolerance (a lower
    compression is better)."""
    if objective == "endurance":
        return a.value > b.value * (1.0 + CHECK_RELATIVE)
    if objective == "compression":
        return a.value < b.value * (1.0 - CHECK_RELATIVE)
    return a.value > b.value + CHECK_SHARE_PCT


def _agree(a: Score, b: Score, objective: str) -> bool:
    """Whether two scores agree within the check tolerance (two unlimited ones do)."""
    if math.isinf(a.value) or math.isinf(b.value):
        return a.value == b.value
    if objective.startswith("capable-"):
        return abs(a.value - b.value) <= CHECK_SHARE_PCT
    return abs(a.value - b.value) <= CHECK_RELATIVE * max(abs(a.value), 1e-12)


def _show(value: float, objective: str) -> str:
    if objective == "compression":
        return f"{value:.0f} N"
    if objective != "endurance":
        return f"{value:.2f} % capable"
    return "unlimited" if math.isinf(value) else f"{value:.3f} min"


@dataclass(frozen=True)
class SweepPoint:
    """The objective by the re-solved IK at one value [m] of a design variable, and whether
    that IK achieved every level the design kept (if not, the task is not held there and
    the objective means nothing)."""

    value_m: float
    score: Score
    kept: bool


def sweep(design: Design, values: Sequence[float]) -> list[SweepPoint]:
    """The objective by the re-solved IK (the file's solver) at each value [m] of the one
    design variable, the rest as in the file: an independent check of the optimum."""
    problem, quantity = design.problem, design.free[0]
    kept = [int(name.split(":")[0]) for name in design.kept]
    out = []
    for value in values:
        at = problem_from_data(problem.data, problem.path, dict.fromkeys(quantity.keys, value))
        answer = static.solve(at)
        held = all(answer.levels[k - 1].achieved for k in kept)
        out.append(SweepPoint(float(value), score(answer, design.objective), held))
    return out
