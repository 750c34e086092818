"""Both IK solvers on the same problem from the same start, and whether they agree."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from casadi_posture.frames import frame
from casadi_posture.ik.result import IKResult
from casadi_posture.ik.solvers import cached_solver
from casadi_posture.problem import Problem

#: Agreement: the same residual per level [task units] and, where the posture is unique,
#: the same joint angles [deg]. Both solvers stop at about 1e-8 of residual; a joint
#: angle follows to about residual / lever arm, so 1e-3 deg leaves room for both.
RESIDUAL_TOLERANCE = 1e-6
JOINT_TOLERANCE_DEG = 1e-3


@dataclass(frozen=True)
class Comparison:
    """The two results on one problem, the largest joint difference [deg] and a verdict;
    ``criterion`` the index of the level that is only minimised (comfort), or None."""

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


def compare(problem: Problem) -> Comparison:
    """Solve ``problem`` with both solvers from its posture and explain any disagreement."""
    hierarchy = problem.hierarchy()
    ns = cached_solver("nullspace", hierarchy, problem.spec.solver).solve(problem.posture)
    lx = cached_solver("lexicographic", hierarchy, problem.spec.solver).solve(problem.posture)
    difference = float(np.max(np.abs(np.degrees(ns.q - lx.q))))
    criterion = hierarchy.criterion_level()
    agree, verdict = _verdict(ns, lx, difference, criterion)
    return Comparison(
        str(problem.path),
        list(problem.body.dof_names),
        hierarchy.level_names(),
        hierarchy.level_units(),
        criterion,
        ns,
        lx,
        difference,
        agree,
        verdict,
    )


def _verdict(
    ns: IKResult, lx: IKResult, difference: float, criterion: int | None
) -> tuple[bool, str]:
    """Whether the solvers agree, and why not; the ``criterion`` level (minimised, not a
    target) is never called unreachable."""
    failed = [r for r in (ns, lx) if not r.success]
    if failed:
        return False, "; ".join(f"{r.solver} failed: {r.status}" for r in failed)
    gap = np.abs(ns.residuals - lx.residuals)
    unreachable = [
        k + 1
        for k in range(gap.size)
        if k != criterion and min(ns.residuals[k], lx.residuals[k]) > RESIDUAL_TOLERANCE
    ]
    if np.any(gap > RESIDUAL_TOLERANCE):
        k = int(np.argmax(gap > RESIDUAL_TOLERANCE)) + 1
        if k in unreachable:
            return False, (
                f"level {k} unreachable in both, ended in different local minima "
                f"({ns.residuals[k - 1]:.3g} vs {lx.residuals[k - 1]:.3g})"
            )
        return False, f"level {k} residual differs by {gap[k - 1]:.3g}"
    note = f"; level {', '.join(map(str, unreachable))} unreachable" if unreachable else ""
    if difference > JOINT_TOLERANCE_DEG:
        return False, f"same residuals, two posture families ({difference:.3g} deg apart){note}"
    return True, "agree" + note


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
            }
        )
    return out
