"""How the solvers and the simulation scale with the body: 2 to 42 DOF (not a test).

Run: python benchmarks/scaling.py [--repeat N] [--sizes 2,7,14,28,42] [--simulate 2,7,14,28,42]

On the benchmark humanoids (``benchmarks/trees.py``, files in ``benchmarks/problems/``),
per number of DOF n:

- build: wall time and memory (resident growth, in a fresh process) of each solver;
- per iteration: one nullspace iteration (posture time / iterations) against a plain
  numpy Baerlocher–Boulic reference written here (full n×n projectors, an SVD
  pseudo-inverse per level, the clamping loop recomputed from scratch), which calls the
  same compiled residual and Jacobian function;
- per posture: nullspace, reference and lexicographic, from the upright start (the zero
  posture clipped into the ranges) and a warm one (the solution moved 0.5° per joint),
  without and with an active inequality aᵀq ≤ b (the right shoulder's flexion held 5° below
  its solution); the methods run interleaved, one call each in turn, and the medians are
  printed;
- agreement: the largest difference of the level residuals between the nullspace solver and
  the lexicographic one and the reference, and each one's status;
- a 20-minute simulation per solver from the file's posture (warm: the targets' own
  posture) and from upright: steps, the steps the other solver took over (fallbacks), the
  largest difference of the two solvers' postures over the steps both ran, wall time, share
  of it outside the IK; peak memory of ``casadi-posture simulate`` at the largest n.
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import numpy as np
import trees

from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceSolver
from casadi_posture.ik.result import IKResult
from casadi_posture.output.report import table
from casadi_posture.problem import Problem, load_problem
from casadi_posture.simulation import simulate

#: The reference's settings: those of the package's nullspace solver (damping 1e-3, rank
#: threshold 1e-9, stop at a 1e-10 rad step), task errors clamped the same way.
DAMPING, RANK, TOLERANCE, MAX_ITERATIONS = 1e-3, 1e-9, 1e-10, 1000


class NumpyReference:
    """Baerlocher & Boulic (2004) in plain numpy: per iteration, every level's residual and
    Jacobian from the hierarchy's compiled function, then for each clamping pass the whole
    recursion J̃_k = J_k P_{k-1}, Δq_k = Δq_{k-1} + J̃_k^{+λ}(Δx_k − J_k Δq_{k-1}),
    P_k = P_{k-1} − J̃_k⁺J̃_k with n×n projectors, until no new joint leaves its range."""

    def __init__(self, hierarchy: TaskHierarchy) -> None:
        self.h = hierarchy
        self.lower, self.upper = hierarchy.body.lower, hierarchy.body.upper

    def _errors(self, k: int, e: np.ndarray) -> np.ndarray:
        out = np.empty_like(e)
        for task, rows in self.h.blocks[k]:
            norm = np.linalg.norm(e[rows])
            out[rows] = -e[rows] * min(1.0, task.step_limit / max(norm, 1e-300))
        return out

    def iteration(self, q: np.ndarray, inequality: Inequality | None) -> np.ndarray:
        """The next posture [rad]."""
        values = self.h.function(q, self.h.targets)
        depth, n = self.h.depth, q.size
        levels = [
            (np.asarray(values[depth + k]), self._errors(k, np.asarray(values[k]).ravel()))
            for k in range(depth)
        ]
        clamped = np.zeros(n, dtype=bool)
        target = np.zeros(n)
        active = False
        while True:
            projector = np.diag((~clamped).astype(float))
            dq = np.where(clamped, target - q, 0.0)
            hard = []
            if active:
                hard = [(inequality.a[None, :], np.array([inequality.b - inequality.a @ q]), 1e-9)]
            for jac, dx, damping in [*hard, *((j, e, DAMPING) for j, e in levels)]:
                jt = jac @ projector
                u, s, vt = np.linalg.svd(jt, full_matrices=False)
                rank = s > RANK  # directions below the threshold take no step either
                damped = s[rank] / (s[rank] ** 2 + damping**2)
                dq = dq + vt[rank].T @ (damped * (u[:, rank].T @ (dx - jac @ dq)))
                projector = projector - vt[rank].T @ vt[rank]
            q_next = q + dq
            low = ~clamped & (q_next < self.lower - 1e-12)
            high = ~clamped & (q_next > self.upper + 1e-12)
            violated = (
                inequality is not None
                and not active
                and inequality.a @ q_next > inequality.b + 1e-12
            )
            if not (low.any() or high.any() or violated):
                return np.clip(q_next, self.lower, self.upper)
            target = np.where(low, self.lower, np.where(high, self.upper, target))
            clamped |= low | high
            active = active or violated

    def solve(self, q0: np.ndarray, inequality: Inequality | None = None) -> tuple[np.ndarray, int]:
        """Iterate from ``q0`` until the step is below the tolerance; the posture, iterations."""
        q = np.clip(q0, self.lower, self.upper)
        for iteration in range(1, MAX_ITERATIONS + 1):
            q_next = self.iteration(q, inequality)
            step = np.max(np.abs(q_next - q))
            q = q_next
            if step < TOLERANCE:
                return q, iteration
        return q, MAX_ITERATIONS


def interleaved(runs: dict[str, Callable[[], object]], repeat: int) -> dict[str, float]:
    """Median wall time [s] of each run over ``repeat`` rounds, one call of each per round
    in turn (after one warm-up call each), so that the machine's noise falls on all alike."""
    for run in runs.values():
        run()
    times: dict[str, list[float]] = {name: [] for name in runs}
    for _ in range(repeat):
        for name, run in runs.items():
            start = time.perf_counter()
            run()
            times[name].append(time.perf_counter() - start)
    return {name: statistics.median(values) for name, values in times.items()}


def build_cost(n: int, solver: str) -> tuple[float, float]:
    """Wall time [s] and resident-memory growth [MB] of building ``solver`` at n DOF, measured
    in a fresh process (after the problem and its hierarchy are loaded)."""
    kind = "NullspaceSolver" if solver == "nullspace" else "LexicographicSolver"
    code = f"""
import time
import trees
from casadi_posture.ik.{solver} import {kind} as Solver
hierarchy = trees.load({n}).hierarchy()
def memory(field):
    return next(int(l.split()[1]) / 1024 for l in open("/proc/self/status") if l.startswith(field))
before = memory("VmRSS")
start = time.perf_counter()
Solver(hierarchy)
print(time.perf_counter() - start, memory("VmHWM") - before)
"""
    out = subprocess.run(
        [sys.executable, "-c", code],
        cwd=Path(__file__).parent,
        capture_output=True,
        text=True,
        check=True,
    )
    elapsed, memory = out.stdout.split()
    return float(elapsed), float(memory)


def simulate_peak_memory(n: int, solver: str) -> float:
    """Peak resident memory [MB] of ``casadi-posture simulate`` on the n-DOF problem, figures
    included, as the process itself reports it when the command returns."""
    code = """
import resource, sys
from casadi_posture.console import main
try:
    main()
except SystemExit as stop:
    assert stop.code in (0, 1), stop.code
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, file=sys.stderr)
"""
    with tempfile.TemporaryDirectory() as out:
        command = ["simulate", str(trees.HERE / f"humanoid_{n}.toml"), "--solver", solver]
        done = subprocess.run(
            [sys.executable, "-c", code, *command, "--out", f"{out}/run"],
            capture_output=True,
            text=True,
            check=True,
        )
    return float(done.stderr.strip().splitlines()[-1])


def _status(iterations: int) -> str:
    """The reference's status from its iteration count."""
    return "converged" if iterations < MAX_ITERATIONS else "max_iterations"


def simulation_rows(problem: Problem, upright: np.ndarray) -> list[list[object]]:
    """Per start (the file's posture, upright [rad]) and solver, a row of the simulations
    table: steps, fallbacks, their complement [%], the largest difference of the two solvers'
    postures over the steps both ran [deg], wall time [s], share outside the IK [%], reused
    steps, why it stopped."""
    names = {d.name: math.degrees(v) for d, v in zip(problem.body.dofs, upright, strict=True)}
    rows = []
    for start_name, start in (("file", problem), ("upright", problem.with_posture(names))):
        runs = {}
        for solver in ("nullspace", "lexicographic"):
            begin = time.perf_counter()
            runs[solver] = (simulate(start, solver), time.perf_counter() - begin)
        ns_q, lx_q = (run.timeline.q for run, _ in runs.values())
        both = min(len(ns_q), len(lx_q))
        apart = math.degrees(float(np.max(np.abs(ns_q[:both] - lx_q[:both]))))
        for solver, (run, wall) in runs.items():
            steps = run.timeline.time.size
            rows.append(
                [
                    problem.body.n,
                    start_name,
                    solver,
                    steps,
                    run.ik_fallbacks,
                    100 * (1 - run.ik_fallbacks / steps),
                    apart,
                    wall,
                    100 * (1 - run.ik_time_s / wall),
                    run.ik_reused,
                    run.stop,
                ]
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--sizes", default=",".join(map(str, trees.SIZES)))
    parser.add_argument(
        "--simulate", default=",".join(map(str, trees.SIZES)), help="sizes to simulate 20 minutes"
    )
    args = parser.parse_args()
    sizes = [int(v) for v in args.sizes.split(",")]
    rng = np.random.default_rng(2026)
    build_rows, posture_rows, sim_rows = [], [], []
    for n in sizes:
        problem = load_problem(trees.HERE / f"humanoid_{n}.toml")
        hierarchy = problem.hierarchy()
        ns_build, ns_memory = build_cost(n, "nullspace")
        lx_build, lx_memory = build_cost(n, "lexicographic")
        build_rows.append([n, hierarchy.depth, ns_build, ns_memory, lx_build, lx_memory])
        ns, lx, ref = (
            NullspaceSolver(hierarchy),
            LexicographicSolver(hierarchy),
            NumpyReference(hierarchy),
        )
        solution = lx.solve(problem.posture).q  # from the random posture the targets are at
        shoulder = problem.body.index["shoulder_flexion_r"]
        held = Inequality(np.eye(n)[shoulder], float(solution[shoulder] - np.radians(5.0)))
        warm = np.clip(
            solution + np.radians(0.5) * rng.choice([-1.0, 1.0], n),
            problem.body.lower,
            problem.body.upper,
        )
        upright = np.clip(np.zeros(n), problem.body.lower, problem.body.upper)
        for start_name, start in (("upright", upright), ("warm", warm)):
            for label, inequality in (("none", None), ("active", held)):
                results: dict[str, IKResult] = {
                    "ns": ns.solve(start, inequality),
                    "lx": lx.solve(start, inequality),
                }
                q_ref, ref_iterations = ref.solve(start, inequality)
                times = interleaved(
                    {
                        "ns": partial(ns.solve, start, inequality),
                        "ref": partial(ref.solve, start, inequality),
                        "ref_iteration": partial(ref.iteration, start, inequality),
                        "lx": partial(lx.solve, start, inequality),
                    },
                    args.repeat,
                )
                ns_result, lx_result = results["ns"], results["lx"]
                ns_iteration = times["ns"] / max(ns_result.iterations, 1)
                ref_residuals = hierarchy.residual_norms(q_ref)
                posture_rows.append(
                    [
                        n,
                        start_name,
                        label,
                        1e3 * ns_iteration,
                        1e3 * times["ref_iteration"],
                        ns_iteration / times["ref_iteration"],
                        ns_result.iterations,
                        ref_iterations,
                        1e3 * times["ns"],
                        1e3 * times["ref"],
                        1e3 * times["lx"],
                        f"{ns_result.residuals[0]:.1e}",
                        f"{lx_result.residuals[0]:.1e}",
                        f"{np.max(np.abs(ns_result.residuals - lx_result.residuals)):.1e}",
                        f"{np.max(np.abs(ns_result.residuals - ref_residuals)):.1e}",
                        f"{ns_result.status} / {lx_result.status} / {_status(ref_iterations)}",
                    ]
                )
        if n in [int(v) for v in args.simulate.split(",") if v]:
            sim_rows += simulation_rows(problem, upright)
    print("Build (in a fresh process each)\n")
    print(
        table(
            ["n", "levels", "NS build (s)", "NS memory (MB)", "LX build (s)", "LX memory (MB)"],
            build_rows,
            digits=3,
        )
    )
    print("\nPostures (medians over interleaved rounds)\n")
    print(
        table(
            [
                "n",
                "start",
                "inequality",
                "NS iteration (ms)",
                "ref iteration (ms)",
                "NS / ref",
                "NS iterations",
                "ref iterations",
                "NS posture (ms)",
                "ref posture (ms)",
                "LX posture (ms)",
                "NS level 1",
                "LX level 1",
                "NS-LX residuals",
                "NS-ref residuals",
                "status NS / LX / ref",
            ],
            posture_rows,
            digits=3,
        )
    )
    if sim_rows:
        print("\n20-minute simulations (1 s steps)\n")
        print(
            table(
                [
                    "n",
                    "start",
                    "solver",
                    "steps",
                    "fallbacks",
                    "without fallback (%)",
                    "NS-LX posture (deg)",
                    "wall (s)",
                    "outside IK (%)",
                    "reused",
                    "stop",
                ],
                sim_rows,
                digits=3,
            )
        )
        largest = max(int(v) for v in args.simulate.split(","))
        for solver in ("nullspace", "lexicographic"):
            peak = simulate_peak_memory(largest, solver)
            print(
                f"peak memory of casadi-posture simulate ({largest} DOF, {solver}): {peak:.0f} MB"
            )


if __name__ == "__main__":
    main()
