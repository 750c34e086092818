"""Wall time of `casadi-posture design` on the 2-DOF arm and the 29-DOF standing body,
measured in one run (not a test).

Run: python benchmarks/design.py

Per case: the first call (building the NLP: CasADi expressions, IPOPT's derivatives) and a
second call on a new problem object of the same structure (the NLP comes from the cache),
IPOPT's iterations and time, the endurance at the start and the best design, and whether
the IK re-solved at the design agrees with the NLP.
"""

from __future__ import annotations

import time
from pathlib import Path

from casadi_posture.output.report import table
from casadi_posture.problem import load_problem
from casadi_posture.workplace_design import design

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
SHELF = {"tasks[2].target_m[2],tasks[3].target_m[2]": (1.0, 1.6)}
DOT = {"tasks[3].point_m[2],tasks[4].target_m[2]": (0.9, 1.5)}
CASES = [
    # (problem, free keys and bounds [m], levels kept (None: every level achieved at the
    # start), NLP starts)
    ("holding_horizontal.toml", {"tasks[0].point_m[2],tasks[1].target_m[2]": (-0.5, 0.1)}, None, 1),
    ("standing_shelf_box.toml", SHELF, None, 1),
    ("standing_shelf_box.toml", SHELF, None, 4),
    ("standing_wall_horizontal.toml", DOT, None, 1),
    ("standing_wall_horizontal.toml", DOT, 3, 1),
]


def main() -> None:
    rows = []
    for name, free, keep, starts in CASES:
        times = []
        for _ in range(2):
            problem = load_problem(PROBLEMS / name)
            began = time.perf_counter()
            answer = design(problem, free, keep_levels=keep, starts=starts)
            times.append(time.perf_counter() - began)
        rows.append(
            [
                name,
                problem.body.n,
                "all achieved" if keep is None else str(keep),
                starts,
                times[0],
                times[1],
                answer.iterations,
                answer.wall_time_s,
                answer.status,
                answer.best_m[0],
                answer.start.value,
                answer.best.value,
                answer.check.value,
                "yes" if answer.agrees else "no",
            ]
        )
    headers = [
        "problem",
        "DOF",
        "levels kept",
        "starts",
        "first call (s)",
        "cached (s)",
        "IPOPT iterations",
        "IPOPT (s)",
        "status",
        "best (m)",
        "start (min)",
        "best (min)",
        "re-solved (min)",
        "agrees",
    ]
    print(table(headers, rows, digits=3))


if __name__ == "__main__":
    main()
