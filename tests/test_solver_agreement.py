"""Both IK solvers, and a plain numpy Baerlocher–Boulic iteration written in the benchmark,
agree on every benchmark body (2 to 42 DOF): the same residual per priority level and, from
a warm start, the same posture."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import trees
from scaling import NumpyReference

from casadi_posture.ik.hierarchy import Inequality
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceSolver


@pytest.fixture(scope="module", params=trees.SIZES, ids=lambda n: f"{n}dof")
def bench(request: pytest.FixtureRequest):
    problem = trees.load(request.param)
    hierarchy = problem.hierarchy()
    lx = LexicographicSolver(hierarchy)
    solution = lx.solve(problem.posture)
    assert solution.success
    return problem, hierarchy, lx, NullspaceSolver(hierarchy), solution.q


def test_the_benchmark_files_are_what_the_generator_writes() -> None:
    for n in trees.SIZES:
        written = (trees.HERE / f"humanoid_{n}.toml").read_text()
        assert written.split("\n", 1)[1] == trees.to_toml(trees.problem_data(n)) + "\n", n


@pytest.mark.parametrize("held", [False, True], ids=["free", "inequality"])
def test_solvers_and_the_numpy_reference_agree_from_a_warm_start(bench, held: bool) -> None:
    problem, hierarchy, lx, ns, solution = bench
    n = problem.body.n
    inequality = None
    if held:
        shoulder = problem.body.index["shoulder_flexion_r"]
        bound = solution[shoulder] - np.radians(5.0)
        inequality = Inequality(np.eye(n)[shoulder], float(bound))
    sign = np.random.default_rng(n).choice([-1.0, 1.0], n)
    start = np.clip(solution + np.radians(0.5) * sign, problem.body.lower, problem.body.upper)
    a, b = lx.solve(start, inequality), ns.solve(start, inequality)
    q_ref, _ = NumpyReference(hierarchy).solve(start, inequality)
    reference = hierarchy.residual_norms(q_ref)
    assert a.success, a.status
    if b.status == "stalled":  # an inequality in conflict with a higher level (2 DOF)
        assert held and a.residuals[0] > 1e-4
        return
    assert b.success, b.status
    assert np.max(np.abs(a.residuals - b.residuals)) < 1e-6
    assert np.max(np.abs(b.residuals - reference)) < 1e-6
    assert np.max(np.abs(a.q - b.q)) < 1e-4  # rad: the lowest level (posture) is full rank
    assert a.residuals[0] < 1e-8 and b.residuals[0] < 1e-8
