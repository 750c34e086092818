"""Speed of the two IK solvers on every shipped problem with tasks (not a test).

Run: python benchmarks/solvers.py [--repeat N]

Per problem, without and with an active inequality aᵀq ≤ b (the shoulder held
5° below its solution), from the solution perturbed by (+8°, -8°) and by (+0.5°, -0.5°),
about one time step:
- median wall time of one nullspace iteration (the compiled call and the numeric sweep);
- iterations and median wall time of a nullspace posture to convergence;
- median wall time of a lexicographic posture, the number of NLPs it solved, and
  that time over (NLPs solved × the IPOPT per-call floor);
- the IPOPT floor: median wall time of an empty 1-variable NLP through CasADi.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import numpy as np

from casadi_posture.ik.hierarchy import Inequality
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceSolver
from casadi_posture.output.report import table
from casadi_posture.problem import load_problem

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def median_time(run: Callable[[], object], repeat: int) -> float:
    """Median wall time of ``run`` [s] over ``repeat`` calls, after one warm-up call."""
    run()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def ipopt_floor(repeat: int) -> float:
    """Median time [s] of an empty 1-variable NLP solved by IPOPT through CasADi."""
    x = ca.SX.sym("x")
    solver = ca.nlpsol(
        "floor",
        "ipopt",
        {"x": x, "f": x**2},
        {
            "expand": True,
            "print_time": False,
            "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-8, "mu_init": 1e-4},
        },
    )
    return median_time(lambda: solver(x0=0.0), repeat)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=200)
    args = parser.parse_args()
    floor = ipopt_floor(args.repeat)
    rows = []
    for path in sorted(PROBLEMS.glob("*.toml")):
        problem = load_problem(path)
        if not problem.tasks:
            continue
        hierarchy = problem.hierarchy()
        ns, lx = NullspaceSolver(hierarchy), LexicographicSolver(hierarchy)
        solution = ns.solve(problem.posture).q
        held = Inequality(np.eye(solution.size)[0], float(solution[0] - math.radians(5.0)))
        cases = [
            (d, label, i) for d in (8.0, 0.5) for label, i in (("none", None), ("active", held))
        ]
        for offset, label, inequality in cases:
            start = np.clip(
                solution + np.radians([offset, -offset])[: solution.size],
                problem.body.lower,
                problem.body.upper,
            )
            per_iteration = median_time(
                lambda s=start, i=inequality, f=ns.iteration: f(s, i), args.repeat * 10
            )
            ns_result = ns.solve(start, inequality)
            ns_posture = median_time(lambda s=start, i=inequality, m=ns: m.solve(s, i), args.repeat)
            lx_result = lx.solve(start, inequality)
            lx_posture = median_time(lambda s=start, i=inequality, m=lx: m.solve(s, i), args.repeat)
            solved = lx_result.subproblems
            rows.append(
                [
                    path.stem,
                    hierarchy.depth,
                    offset,
                    label,
                    1e6 * per_iteration,
                    ns_result.iterations,
                    1e3 * ns_posture,
                    1e3 * lx_posture,
                    lx_result.iterations,
                    solved,
                    lx_posture / (solved * floor),
                    "ok" if ns_result.success and lx_result.success else "FAILED",
                ]
            )
    print(f"IPOPT per-call floor (empty 1-variable NLP): {1e3 * floor:.3f} ms\n")
    print(
        table(
            [
                "problem",
                "levels",
                "start offset (deg)",
                "inequality",
                "NS iteration (µs)",
                "NS iterations",
                "NS posture (ms)",
                "LX posture (ms)",
                "LX iterations",
                "LX NLPs",
                "LX / (NLPs × floor)",
                "status",
            ],
            rows,
            digits=2,
        )
    )


if __name__ == "__main__":
    main()
