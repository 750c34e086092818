"""Both IK solvers on every shipped problem, from the same start: residuals per level,
whether they agree, and how long each took.

Run: python examples/compare_solvers.py [PROBLEM_FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path

import casadi_posture as cp

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def compare_folder(folder: Path) -> list[cp.Comparison]:
    """One comparison per problem file of ``folder`` that has tasks."""
    problems = [cp.load(path) for path in sorted(folder.glob("*.toml"))]
    return [cp.compare(problem) for problem in problems if problem.tasks]


def main(folder: Path = PROBLEMS) -> list[cp.Comparison]:
    comparisons = compare_folder(folder)
    for c in comparisons:
        worst = max(max(c.nullspace.residuals), max(c.lexicographic.residuals))
        print(
            f"{Path(c.problem).stem:24s} {c.verdict:6s} largest residual {worst:.1e}, "
            f"postures {c.max_joint_difference_deg:.1e} deg apart, "
            f"nullspace {1e3 * c.nullspace.wall_time_s:.2f} ms, "
            f"lexicographic {1e3 * c.lexicographic.wall_time_s:.2f} ms"
        )
    return comparisons


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else PROBLEMS)
