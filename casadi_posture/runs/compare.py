"""Both IK solvers on the same problem from the same start, and whether they agree; from
random starts too, and whether an answer both share is a local minimum or out of reach."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.frames import frame
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.reach import at_bounds, beyond_reach, random_starts
from casadi_posture.ik.result import ACHIEVED_TOLERANCE, IKResult
from casadi_posture.ik.solvers import SOLVER_NAMES, cached_solver
from casadi_posture.problem import Problem

#: Agreement: the same residual per level [task units] and, where the posture is unique,
#: the same joint angles [deg]. Both solvers stop at about 1e-8 of residual; a joint
#: angle follows to about residual / lever arm, so 1e-3 deg leaves room for both.
RESIDUAL_TOLERANCE = 1e-6
JOINT_TOLERANCE_DEG = 1e-3


@dataclass(frozen=True)
class Comparison:
    """The two results on one problem from ``start`` [rad], the largest joint difference
    [deg], a verdict and its ``outcome`` (``REACHED``, ``LOCAL_MINIMUM``, ``UNREACHABLE``
    or ``DIFFER``); ``criterion`` the index of the level that is only minimised (comfort),
    or None; ``starts`` the comparisons from random starts, when asked for."""

    problem: str
    dofs: list[str]
    levels: list[str]
    units: list[str]
    criterion: int | None
    nullspace: IKResult
    lexicographic: IKResult
    max_joint_difference_deg: float
    agree: bool
    verdict: str
    outcome: str
    start: np.ndarray
    starts: Starts | None = None

    def to_frame(self) -> object:
        """One row per priority level as a pandas DataFrame (the columns of compare.csv)."""
        return frame(rows(self))

    def postures_frame(self) -> object:
        """One row per DOF as a pandas DataFrame: each solver's angle and their difference
        [deg]."""
        nullspace, lexicographic = np.degrees(self.nullspace.q), np.degrees(self.lexicographic.q)
        return frame(
            {
                "dof": self.dofs,
                "nullspace_deg": nullspace,
                "lexicographic_deg": lexicographic,
                "difference_deg": nullspace - lexicographic,
            }
        )


def compare(problem: Problem, starts: int = 0, seed: int = 0) -> Comparison:
    """Solve ``problem`` with both solvers from its posture and explain any disagreement;
    with ``starts``, also from that many postures drawn uniformly within the joint limits
    (``random_starts`` of ``seed``), summed up in ``Comparison.starts``. Each solver is
    built once and solves from every start. An answer both solvers share that misses a
    level is judged against every answer found (at least ``CHECK_STARTS`` random starts
    then) and the chain's reach: a local minimum when another start reaches the level, else
    unreachable, saying on which evidence."""
    if not 0 <= starts <= MAX_STARTS:
        raise ValueError(f"starts = {starts}: expected 0 to {MAX_STARTS}")
    hierarchy = problem.hierarchy()
    solvers = [cached_solver(name, hierarchy, problem.spec.solver) for name in SOLVER_NAMES]
    criterion = hierarchy.criterion_level()
    drawn = random_starts(problem.body, starts, seed)
    solved = [tuple(s.solve(q0) for s in solvers) for q0 in [problem.posture, *drawn]]
    if any(_missed(pair, criterion) for pair in solved):
        extra = random_starts(problem.body, CHECK_STARTS, seed)[starts:]
        checked = [tuple(s.solve(q0) for s in solvers) for q0 in extra]
    else:
        checked = []
    evidence = _Evidence(hierarchy, [r for pair in solved + checked for r in pair])
    mine = _comparison(problem, hierarchy, problem.posture, solved[0], evidence)
    if not starts:
        return mine
    others = [
        _comparison(problem, hierarchy, q0, pair, evidence)
        for q0, pair in zip(drawn, solved[1:], strict=True)
    ]
    return replace(mine, starts=Starts.of(others, seed))


#: The most random starts ``compare`` takes (each solves the problem twice).
MAX_STARTS = 1000

#: Random starts within the joint limits whose answers (both solvers') the global check
#: weighs at least, when an answer misses a level.
CHECK_STARTS = 16


@dataclass(frozen=True)
class Starts:
    """Both solvers from ``count`` random starts (``random_starts`` of ``seed``): how many
    agree, and of those how many reach every target level, stop at a local minimum or at a
    target out of reach; how many differ; the largest joint difference [deg] and residual
    difference (``worst_residual_gap``, in ``worst_gap_unit``) over the starts; each
    start's comparison."""

    count: int
    seed: int
    agree: int
    reached: int
    local_minimum: int
    unreachable: int
    differ: int
    worst_joint_difference_deg: float
    worst_residual_gap: float
    worst_gap_unit: str
    comparisons: tuple[Comparison, ...]

    @classmethod
    def of(cls, comparisons: list[Comparison], seed: int) -> Starts:
        """The summary of the comparisons from random starts of ``seed``; the residual gap
        is the largest of a target level's (not the criterion's, whose minima differ in a
        way the joint difference shows)."""
        first = comparisons[0]
        targets = [k for k in range(len(first.levels)) if k != first.criterion]
        gaps = np.array(
            [np.abs(c.nullspace.residuals - c.lexicographic.residuals) for c in comparisons]
        )[:, targets]
        start, level = np.unravel_index(int(np.argmax(gaps)), gaps.shape)
        outcomes = [c.outcome for c in comparisons]
        return cls(
            len(comparisons),
            seed,
            sum(c.agree for c in comparisons),
            outcomes.count(REACHED),
            outcomes.count(LOCAL_MINIMUM),
            outcomes.count(UNREACHABLE),
            sum(not c.agree for c in comparisons),
            max(c.max_joint_difference_deg for c in comparisons),
            float(gaps[start, level]),
            first.units[targets[level]],
            tuple(comparisons),
        )

    def line(self) -> str:
        """The summary in one line."""
        return (
            f"{self.count} random starts (seed {self.seed}): {self.agree} agree ({self.reached} "
            f"reach the task, {self.local_minimum} at a local minimum, {self.unreachable} "
            f"unreachable), {self.differ} differ; worst disagreement "
            f"{self.worst_joint_difference_deg:.3g} deg, "
            f"{amount(self.worst_residual_gap, self.worst_gap_unit)}"
        )


#: What a comparison found: both solvers achieve every target level; both stop at the same
#: local minimum; both stop where a level is out of reach; they differ (or one failed).
REACHED, LOCAL_MINIMUM, UNREACHABLE, DIFFER = "reached", "local minimum", "unreachable", "differ"


def _comparison(
    problem: Problem,
    hierarchy: TaskHierarchy,
    start: np.ndarray,
    pair: tuple[IKResult, IKResult],
    evidence: _Evidence,
) -> Comparison:
    """The comparison of both solvers' answers ``pair`` from ``start`` [rad]."""
    ns, lx = pair
    difference = float(np.max(np.abs(np.degrees(ns.q - lx.q))))
    agree, verdict, outcome = _verdict(ns, lx, difference, evidence)
    return Comparison(
        str(problem.path),
        list(problem.body.dof_names),
        hierarchy.level_names(),
        hierarchy.level_units(),
        evidence.criterion,
        ns,
        lx,
        difference,
        agree,
        verdict,
        outcome,
        np.asarray(start, dtype=float),
    )


def _missed(pair: tuple[IKResult, ...], criterion: int | None) -> list[int]:
    """The target levels (indices; not the ``criterion``) none of ``pair`` achieves."""
    return [
        k
        for k in range(pair[0].residuals.size)
        if k != criterion and not any(r.achieved[k] for r in pair)
    ]


class _Evidence:
    """Every successful answer both solvers gave on one problem, from any start, and the
    chain's reach: whether an answer that misses a level is a local minimum (another answer
    does better) or the level is out of reach, and why."""

    def __init__(self, hierarchy: TaskHierarchy, answers: list[IKResult]) -> None:
        self.hierarchy = hierarchy
        self.criterion = hierarchy.criterion_level()
        self.starts = len(answers) // 2
        self.residuals = [r.residuals for r in answers if r.success]
        self.targets = [k for k in range(hierarchy.depth) if k != self.criterion]

    def better(self, residuals: np.ndarray) -> tuple[int, float] | None:
        """The first level (index) at which an answer does better than ``residuals`` by
        more than ``ACHIEVED_TOLERANCE`` while doing as well on the levels above, and the
        lowest residual there of such an answer; None when none does."""
        best: tuple[int, float] | None = None
        for other in self.residuals:
            for k in self.targets:
                if other[k] < residuals[k] - ACHIEVED_TOLERANCE:
                    if best is None or (k, other[k]) < best:
                        best = (k, float(other[k]))
                    break
                if other[k] > residuals[k] + ACHIEVED_TOLERANCE:
                    break
        return best

    def out_of_reach(self, k: int, closest: float) -> str:
        """Why level ``k`` (index), which the best answer misses by ``closest``, is out of
        reach: its chain's reach, else that no start reached it (while holding the levels
        above, when one reached it at their expense)."""
        why = beyond_reach(self.hierarchy.body, self.hierarchy.levels[k])
        if why:
            return why
        held = any(r[k] <= ACHIEVED_TOLERANCE for r in self.residuals) * " holding the levels above"
        unit = self.hierarchy.level_units()[k]
        return f"no start of {self.starts} reached it{held}, the closest {amount(closest, unit)}"

    def one_minimum(self, ns: IKResult, lx: IKResult) -> bool:
        """Whether two answers of the same residuals are one minimum: the posture halfway
        between them does as well on every level (where a level is missed its residual is
        stationary, so equal residuals leave the posture to about the square root of their
        tolerance, more than ``JOINT_TOLERANCE_DEG``)."""
        halfway = self.hierarchy.residual_norms((ns.q + lx.q) / 2)
        return bool(np.all(halfway <= np.maximum(ns.residuals, lx.residuals) + RESIDUAL_TOLERANCE))

    def judge(self, result: IKResult, missed: list[int]) -> tuple[str, str]:
        """The outcome of an answer both solvers share (``result``, one of them) that
        misses the levels ``missed`` (indices), and the verdict's note on it: unreachable
        when a level is out of reach (by the chain's reach, or no start reaching it), else
        a local minimum (another start reaches the level); the joints it holds at a limit
        when another start does better."""
        better = self.better(result.residuals)
        shy = [k for k in missed if better is None or k < better[0]]
        notes = [
            f"level {k + 1} unreachable ({self.out_of_reach(k, result.residuals[k])})" for k in shy
        ]
        if better is None:
            return UNREACHABLE, "; ".join(notes)
        k, closest = better
        unit = self.hierarchy.level_units()[k]
        where = _limits(self.hierarchy.body, result.q)
        if closest > ACHIEVED_TOLERANCE:
            notes.append(f"level {k + 1} unreachable ({self.out_of_reach(k, closest)})")
            notes.append(
                f"both at a local minimum ({where}): another start ends "
                f"{amount(closest, unit)} from it"
            )
            return UNREACHABLE, "; ".join(notes)
        notes.append(f"both at a local minimum ({where}): level {k + 1} reached from another start")
        return (UNREACHABLE if shy else LOCAL_MINIMUM), "; ".join(notes)


def amount(value: float, unit: str) -> str:
    """A residual and its unit: '0.066 m', '0.08 (rad, m)' for a level of mixed units, '1.4'
    for the comfort level's unit 1."""
    if unit == "1":
        return f"{value:.3g}"
    return f"{value:.3g} ({unit})" if "," in unit else f"{value:.3g} {unit}"


def _limits(body: BodyModel, q: np.ndarray) -> str:
    """'joint limits: ' and the DOFs ``q`` [rad] holds at a bound, or 'no joint at a limit'."""
    limits = at_bounds(body, q)
    return f"joint limits: {', '.join(limits)}" if limits else "no joint at a limit"


def _verdict(
    ns: IKResult, lx: IKResult, difference: float, evidence: _Evidence
) -> tuple[bool, str, str]:
    """Whether the solvers agree, why not, and the outcome (``REACHED``, ...); the
    criterion level (minimised, not a target) is never called unreachable."""
    missed = _missed((ns, lx), evidence.criterion)
    failed = [r for r in (ns, lx) if not r.success]
    if failed:
        far = [
            (k, beyond_reach(evidence.hierarchy.body, evidence.hierarchy.levels[k])) for k in missed
        ]
        notes = [f"{r.solver} failed: {r.status}" for r in failed]
        notes += [f"level {k + 1} unreachable ({why})" for k, why in far if why]
        return False, "; ".join(notes), DIFFER
    gap = np.abs(ns.residuals - lx.residuals)
    if np.any(gap > RESIDUAL_TOLERANCE):
        return (
            False,
            _gap(ns, lx, int(np.argmax(gap > RESIDUAL_TOLERANCE)), missed, evidence),
            DIFFER,
        )
    outcome, note = evidence.judge(ns, missed) if missed else (REACHED, "")
    note = f"; {note}" if note else ""
    if difference > JOINT_TOLERANCE_DEG and not (missed and evidence.one_minimum(ns, lx)):
        return (
            False,
            f"same residuals, two posture families ({difference:.3g} deg apart){note}",
            DIFFER,
        )
    return True, "agree" + note, outcome


def _gap(ns: IKResult, lx: IKResult, k: int, missed: list[int], evidence: _Evidence) -> str:
    """Why the solvers' residuals differ first at level ``k`` (index): one reaches it and
    the other stops short (where), both miss it in different local minima, or it is out
    of reach."""
    body, unit = evidence.hierarchy.body, evidence.hierarchy.level_units()[k]
    if k not in missed:
        if ns.achieved[k] == lx.achieved[k]:
            return f"level {k + 1} residual differs by {abs(ns.residuals[k] - lx.residuals[k]):.3g}"
        done, short = (ns, lx) if ns.achieved[k] else (lx, ns)
        return (
            f"level {k + 1} reached by {done.solver} only; {short.solver} stops "
            f"{amount(short.residuals[k], unit)} from it ({_limits(body, short.q)})"
        )
    ends = f"{ns.residuals[k]:.3g} vs {amount(lx.residuals[k], unit)}"
    closer = min((ns, lx), key=lambda r: r.residuals[k])
    better = evidence.better(closer.residuals)
    if better is not None and better[0] <= k:
        return (
            f"level {k + 1} missed by both, in different local minima ({ends}); another "
            "start does better"
        )
    why = evidence.out_of_reach(k, closer.residuals[k])
    return f"level {k + 1} unreachable ({why}); the solvers stop {ends} from it"


def rows(comparison: Comparison) -> list[dict[str, object]]:
    """One table row per priority level (the CSV and the screen table)."""
    out = []
    for k, name in enumerate(comparison.levels):
        out.append(
            {
                "problem": comparison.problem,
                "level": k + 1,
                "tasks": name,
                "unit": comparison.units[k],
                "residual_nullspace": float(comparison.nullspace.residuals[k]),
                "residual_lexicographic": float(comparison.lexicographic.residuals[k]),
                "achieved_nullspace": comparison.nullspace.achieved[k],
                "achieved_lexicographic": comparison.lexicographic.achieved[k],
                "criterion": k == comparison.criterion,
                "max_joint_difference_deg": comparison.max_joint_difference_deg,
                "time_nullspace_ms": 1e3 * comparison.nullspace.wall_time_s,
                "time_lexicographic_ms": 1e3 * comparison.lexicographic.wall_time_s,
                "status_nullspace": comparison.nullspace.status,
                "status_lexicographic": comparison.lexicographic.status,
                "verdict": comparison.verdict,
                "outcome": comparison.outcome,
                **starts_columns(comparison.starts),
            }
        )
    return out


def starts_columns(starts: Starts | None) -> dict[str, object]:
    """The random starts' summary as compare.csv's columns (empty without ``starts``)."""
    return {
        column: None if starts is None else getattr(starts, name)
        for column, name in STARTS_COLUMNS.items()
    }


#: compare.csv's columns of the random starts' summary, and the ``Starts`` field of each.
STARTS_COLUMNS = {
    "starts": "count",
    "starts_seed": "seed",
    "starts_agree": "agree",
    "starts_reached": "reached",
    "starts_local_minimum": "local_minimum",
    "starts_unreachable": "unreachable",
    "starts_differ": "differ",
    "starts_worst_joint_difference_deg": "worst_joint_difference_deg",
    "starts_worst_residual_gap": "worst_residual_gap",
    "starts_worst_gap_unit": "worst_gap_unit",
}
