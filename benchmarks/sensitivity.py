"""Wall time of a sensitivity analysis (every input, the posture's derivative included) on the
2-DOF arm, the seated upper body and the 29-DOF standing body, against the time the same
derivatives would take by central finite differences (two IK solves per input).

Run: python benchmarks/sensitivity.py
"""

from __future__ import annotations

import time
from pathlib import Path

import casadi_posture as cp
from casadi_posture.output.report import table
from casadi_posture.sensitivity_analysis.analysis import sensitivity
from casadi_posture.static import solve

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
CASES = ("holding_horizontal", "seated_assembly", "standing_wall_horizontal", "standing_shelf_box")
REPEATS = 3


def main() -> None:
    rows = []
    for name in CASES:
        problem = cp.load(PROBLEMS / f"{name}.toml")
        sensitivity(problem)  # warm the caches a second run would find
        start = time.perf_counter()
        for _ in range(REPEATS):
            result = sensitivity(problem)
        wall = (time.perf_counter() - start) / REPEATS
        start = time.perf_counter()
        for _ in range(REPEATS):
            solve(problem)
        one_solve = (time.perf_counter() - start) / REPEATS
        n = len(result.inputs)
        rows.append([name, problem.body.n, n, wall, one_solve, 2 * n * one_solve])
    print(
        table(
            [
                "problem",
                "DOF",
                "inputs",
                "sensitivity (s)",
                "one IK solve (s)",
                "central FD, 2 solves per input (s)",
            ],
            rows,
            digits=3,
        )
    )


if __name__ == "__main__":
    main()
