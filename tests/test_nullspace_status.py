"""The nullspace solver's status says what happened: a rest that misses a level it could
lower is not ``converged``. On the benchmark bodies (benchmarks/trees.py): a saddle of
level 1 (the 7-DOF arm straight at its elbow limit) is left for the numpy reference's
posture; a joint held at a limit that level 1 pulls away from is reported; from an upright
start both solvers and the reference agree on the levels above the comfort level."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import trees
from conftest import PROBLEMS, SHORT_REACH
from scaling import NumpyReference

import casadi_posture.ik.nullspace as nullspace
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceSolver, _nnls
from casadi_posture.ik.result import ACHIEVED_TOLERANCE
from casadi_posture.ik.tasks import JointReference
from casadi_posture.problem import load_problem


@pytest.fixture(scope="module")
def straight_arm() -> tuple[TaskHierarchy, np.ndarray]:
    """The 7-DOF arm, wrist ▸ every joint upright (the benchmark before its comfort level),
    and the upright start."""
    problem = trees.load(7)
    body = problem.body
    upright = np.clip(np.zeros(body.n), body.lower, body.upper)
    wrist = problem.hierarchy().levels[0][0]
    posture = JointReference("upright", 2, tuple(body.dof_names), tuple(upright))
    return TaskHierarchy(body, [wrist, posture]), upright


def test_a_saddle_of_level_1_is_not_converged(straight_arm, monkeypatch) -> None:
    """Without a restart the run rests with the arm straight at its elbow limit, the wrist
    6.0 cm beyond the target along the arm: the status says so."""
    hierarchy, upright = straight_arm
    monkeypatch.setattr(nullspace, "SADDLE_RESTARTS", 0)
    result = NullspaceSolver(hierarchy).solve(upright)
    assert result.status.startswith("stalled: level 1 at a saddle") and not result.success
    assert result.residuals[0] == pytest.approx(0.0603, abs=5e-4)
    assert "elbow_flexion_r" in result.at_limits


def test_the_saddle_is_left_for_the_references_posture(straight_arm) -> None:
    hierarchy, upright = straight_arm
    result = NullspaceSolver(hierarchy).solve(upright)
    q_ref, iterations = NumpyReference(hierarchy).solve(upright)
    assert result.success, result.status
    assert iterations < 1000 and result.residuals[0] < 1e-9
    assert np.max(np.abs(result.residuals - hierarchy.residual_norms(q_ref))) < 1e-6
    assert np.max(np.abs(result.q - q_ref)) < 1e-5


def test_nnls_against_a_hand_solution() -> None:
    """min ‖a x - b‖, x ≥ 0: b = a (1, -1) = (1, -1, 0); with x2 = 0 the best x1 is
    (1·1 + 1·0) / (1 + 1) = 0.5, and the gradient in x2 there, (0, 1, 1)·(b - a x) = -1.5,
    keeps x2 at 0. A nonnegative optimum is returned as it is."""
    a = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    assert np.allclose(_nnls(a, np.array([1.0, -1.0, 0.0])), [0.5, 0.0])
    assert np.allclose(_nnls(a, a @ np.array([0.5, 2.0])), [0.5, 2.0])


#: A step of the 20-minute simulation of the 28-DOF benchmark body (benchmarks/trees.py) under
#: the paper's active strategy on the right hip flexion, level 1 (the ankles) lost: its start
#: [deg] and the linearised fatigue constraint aᵀq ≤ b (a on the right leg's DOFs).
START_DEG = [
    16.2072089, -9.29661032, 56.2851534, 64.8121599, -31.9589435, 63.5394396, -0.0151349662,
    0.182339793, 0.0571786882, 16.8376391, 45.0, -40.0, 81.6262441, -20.0, 30.0, 58.3516436,
    18.2681042, 11.8772879, 113.253788, -0.000158359391, -0.466959993, 0.0280436313,
    30.1233212, 12.3272161, -17.7025229, 92.6118968, 0.364589494, 0.0151167047,
]  # fmt: skip
RIGHT_LEG_A = [0.991094965, -0.0778890301, -0.0997647601, -0.0411104255, 0.00423588124,
               -0.0017472612]  # fmt: skip
BOUND = 0.221158929343


def test_a_limit_level_1_pulls_away_from_is_not_converged() -> None:
    """The clamping loop comes to rest with the right hip abduction held at its upper limit
    (the sweep's step takes it beyond) although the feet level pulls it back inside: the
    ankles 0.348 m off their targets, where the lexicographic solver reaches 0.286 m. The
    numpy reference rests there too; the status says the level could go lower."""
    problem = trees.load(28)
    hierarchy, body = problem.hierarchy(), problem.body
    a = np.zeros(body.n)
    a[body.index["hip_flexion_r"] : body.index["hip_flexion_r"] + 6] = RIGHT_LEG_A
    held = Inequality(a, BOUND)
    start = np.radians(START_DEG)
    result = NullspaceSolver(hierarchy).solve(start, held)
    best = LexicographicSolver(hierarchy).solve(start, held)
    q_ref, _ = NumpyReference(hierarchy).solve(start, held)
    assert best.success and best.residuals[0] == pytest.approx(0.286, abs=1e-3)
    assert hierarchy.residual_norms(q_ref)[0] == pytest.approx(0.348, abs=1e-3)
    assert result.residuals[0] == pytest.approx(0.348, abs=1e-3)
    assert result.status.startswith("stalled: level 1 held at a limit") and not result.success
    assert "hip_abduction_r" in result.at_limits


def test_a_bound_that_level_1_rests_against_converges_with_the_lexicographic_optimum() -> None:
    """The 2-DOF arm with its shoulder flexion bounded: the run converges (it was called
    stalled when an iterate 9e-6 rad before the rest had level 2 lower by 7e-6) at the
    lexicographic solver's residuals."""
    problem = trees.load(2)
    body, hierarchy = problem.body, problem.hierarchy()
    shoulder = body.index["shoulder_flexion_r"]
    solution = LexicographicSolver(hierarchy).solve(problem.posture).q
    signs = np.random.default_rng(2026).choice([-1.0, 1.0], 2)  # scaling.py's warm start
    warm = np.clip(solution + np.radians(0.5) * signs, body.lower, body.upper)
    held = Inequality(np.eye(body.n)[shoulder], float(solution[shoulder] - np.radians(5.0)))
    result = NullspaceSolver(hierarchy).solve(warm, held)
    reference = LexicographicSolver(hierarchy).solve(warm, held)
    assert result.success, result.status
    assert np.abs(result.residuals - reference.residuals).max() < 1e-6
    assert result.residuals[0] > 0.02  # the bound keeps the wrist off its target


def test_a_level_out_of_reach_converges_to_the_lexicographic_minimum() -> None:
    """Level 2 out of reach above the comfort level: the run ended ``stalled`` at its start
    (the hands 0.638 m off) while the comfort level, projected on a nullspace that turns
    with every iterate near the straight-arm singularity, kept it oscillating. It converges
    to the lexicographic solver's minimum: feet and balance kept, the hands as close as
    they get (0.1036 m), knees and elbows at their limits."""
    problem = load_problem(PROBLEMS / "standing_shelf_box.toml", SHORT_REACH)
    hierarchy = problem.hierarchy()
    result = NullspaceSolver(hierarchy).solve(problem.posture)
    best = LexicographicSolver(hierarchy).solve(problem.posture)
    assert best.success and best.residuals[1] == pytest.approx(0.1036, abs=5e-4)
    assert result.status == "converged" and result.success
    assert result.residuals[0] < ACHIEVED_TOLERANCE
    assert abs(result.residuals[1] - best.residuals[1]) < 1e-3
    assert set(result.at_limits) == set(best.at_limits)


@pytest.mark.slow
@pytest.mark.parametrize("n", trees.SIZES, ids=lambda n: f"{n}dof")
def test_from_upright_the_levels_above_comfort_agree(n: int) -> None:
    """From the upright start every level above the comfort level is achieved by the three
    (their residuals agree within the achieved tolerance); the comfort level itself may
    end in another local minimum (posture family), which is a fixed point of both solvers."""
    problem = trees.load(n)
    hierarchy = problem.hierarchy()
    upright = np.clip(np.zeros(n), problem.body.lower, problem.body.upper)
    ns, lx = NullspaceSolver(hierarchy), LexicographicSolver(hierarchy)
    a, b = ns.solve(upright), lx.solve(upright)
    q_ref, _ = NumpyReference(hierarchy).solve(upright)
    assert a.success and b.success, (a.status, b.status)
    above = slice(0, hierarchy.depth - 1)
    for residuals in (a.residuals, b.residuals, hierarchy.residual_norms(q_ref)):
        assert np.all(residuals[above] < ACHIEVED_TOLERANCE)
    for q in (a.q, b.q):  # each rest is a rest of the other solver
        assert np.abs(ns.solve(q).residuals - lx.solve(q).residuals).max() < 1e-6
