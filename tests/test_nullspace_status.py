"""The nullspace solver's status says what happened: a rest that misses a level it could
lower is not ``converged``. On the benchmark bodies (benchmarks/trees.py): a saddle of
level 1 (the 7-DOF arm straight at its elbow limit) is left for the numpy reference's
posture; a joint held at a limit that level 1 pulls away from is reported, and released by a
restart; a joint that the held constraint keeps inside is not held; the 28-DOF body's
simulation takes no step from the other solver; from an upright start both solvers and the
reference agree on the levels above the comfort level."""

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
from casadi_posture.simulation import simulate


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


#: Two steps of the 20-minute simulation of the 28-DOF benchmark body (benchmarks/trees.py)
#: under the paper's active strategy on the right hip flexion, level 1 (the ankles) out of reach
#: under the linearised fatigue constraint aᵀq ≤ b (a on the right leg's six DOFs from the hip
#: flexion): the starts [deg], a and b. The simulation alternates between the two; each fell
#: back on the lexicographic solver (57 of its 1201 steps).
START_DEG = [
    16.2072089, -9.29661032, 56.2851534, 64.8121599, -31.9589435, 63.5394396, -0.0151349662,
    0.182339793, 0.0571786882, 16.8376391, 45.0, -40.0, 81.6262441, -20.0, 30.0, 58.3516436,
    18.2681042, 11.8772879, 113.253788, -0.000158359391, -0.466959993, 0.0280436313,
    30.1233212, 12.3272161, -17.7025229, 92.6118968, 0.364589494, 0.0151167047,
]  # fmt: skip
RIGHT_LEG_A = [0.991094965, -0.0778890301, -0.0997647601, -0.0411104255, 0.00423588124,
               -0.0017472612]  # fmt: skip
BOUND = 0.221158929343
OTHER_START_DEG = [
    13.4606871, -9.21136319, 57.9817574, 63.7146828, -26.0362008, 60.8452279, -0.0176480273,
    0.159904284, 0.050252114, 26.1817243, 45.0, -40.0, 82.2981906, -20.0, -20.0, 56.1666387,
    17.9639786, 11.34763, 109.548442, -0.000814831251, -0.410692406, 0.0270190076, 30.0379412,
    12.0675606, -17.9320621, 92.6118968, 0.346752122, 0.0120347539,
]  # fmt: skip
OTHER_RIGHT_LEG_A = [0.71343906, -0.488674079, -0.452329724, -0.216549538, 0.0178928924,
                     -0.0196548949]  # fmt: skip
OTHER_BOUND = -0.0769015857602


@pytest.fixture(scope="module")
def legs() -> tuple[TaskHierarchy, NullspaceSolver, LexicographicSolver]:
    """The 28-DOF benchmark body's hierarchy and both solvers on it."""
    hierarchy = trees.load(28).hierarchy()
    return hierarchy, NullspaceSolver(hierarchy), LexicographicSolver(hierarchy)


def _step(hierarchy: TaskHierarchy, start_deg: list[float], leg: list[float], bound: float):
    """A step's start [rad] and its constraint on the right leg."""
    body = hierarchy.body
    a = np.zeros(body.n)
    a[body.index["hip_flexion_r"] : body.index["hip_flexion_r"] + 6] = leg
    return np.radians(start_deg), Inequality(a, bound)


def test_a_limit_level_1_pulls_away_from_is_not_converged(legs, monkeypatch) -> None:
    """Without a restart, the clamping loop comes to rest with the right hip abduction held
    at its upper limit although the feet level pulls it back inside: the ankles 0.348 m off
    their targets, where the lexicographic solver reaches 0.286 m. The numpy reference (the
    original clamping loop) rests there too; the status says the level could go lower."""
    hierarchy, ns, _ = legs
    monkeypatch.setattr(nullspace, "SADDLE_RESTARTS", 0)
    start, held = _step(hierarchy, START_DEG, RIGHT_LEG_A, BOUND)
    result = ns.solve(start, held)
    q_ref, _ = NumpyReference(hierarchy).solve(start, held)
    assert hierarchy.residual_norms(q_ref)[0] == pytest.approx(0.348, abs=1e-3)
    assert result.residuals[0] == pytest.approx(0.348, abs=1e-3)
    assert result.status.startswith("stalled: level 1 held at a limit") and not result.success
    assert "hip_abduction_r" in result.at_limits


def test_a_limit_level_1_pulls_away_from_is_released(legs) -> None:
    """The restart releases the hip abduction (its multiplier for the feet level is
    negative) and converges to the lexicographic solver's answer: the ankles 0.286 m off,
    the hip abduction inside its range, the constraint active."""
    hierarchy, ns, lx = legs
    start, held = _step(hierarchy, START_DEG, RIGHT_LEG_A, BOUND)
    result, best = ns.solve(start, held), lx.solve(start, held)
    assert best.success and best.residuals[0] == pytest.approx(0.286, abs=1e-3)
    assert result.status == "converged" and result.success
    assert abs(result.residuals[0] - best.residuals[0]) < 1e-6
    assert np.all(result.residuals[1:3] < ACHIEVED_TOLERANCE)
    assert "hip_abduction_r" not in result.at_limits and result.inequality_active


def test_a_joint_the_constraint_keeps_inside_is_not_held(legs) -> None:
    """The other step: the free step of the clamping loop (nothing held) violates the
    constraint and takes the right hip rotation beyond its lower limit, which the constraint,
    once held, keeps inside. Holding both at once (the original loop) moved the hip rotation
    0.43 rad onto its limit, to a rest with the ankles 0.2389 m off, worse than the 0.2224 m
    passed on the way: ``stalled``. Holding first what the step reaches first converges to
    the lexicographic solver's answer (0.2223 m, the same joints at their limits)."""
    hierarchy, ns, lx = legs
    start, held = _step(hierarchy, OTHER_START_DEG, OTHER_RIGHT_LEG_A, OTHER_BOUND)
    result, best = ns.solve(start, held), lx.solve(start, held)
    assert best.success and best.residuals[0] == pytest.approx(0.2223, abs=1e-4)
    assert result.status == "converged" and result.success
    assert abs(result.residuals[0] - best.residuals[0]) < 1e-6
    assert set(result.at_limits) == set(best.at_limits)
    assert "hip_rotation_r" not in result.at_limits
    assert np.abs(result.q - best.q).max() < 1e-3


@pytest.mark.slow
def test_the_28_dof_simulation_does_not_fall_back() -> None:
    """The 20-minute hold of the 28-DOF benchmark body with the nullspace solver, level 1
    lost for good under the paper's constraint: no step takes the other solver's posture."""
    result = simulate(trees.load(28), "nullspace")
    assert result.timeline.time.size == 1201 and result.stop == "completed"
    assert result.ik_fallbacks == 0


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
    to the lexicographic solver's minimum of level 2: feet and balance kept, the hands as
    close as they get (0.1269 m), knees and elbows at their limits. (The lexicographic
    solver then fails the comfort level at that singular minimum and keeps level 2's
    posture: tests/test_lexicographic_reach.py.)"""
    problem = load_problem(PROBLEMS / "standing_shelf_box.toml", SHORT_REACH)
    hierarchy = problem.hierarchy()
    result = NullspaceSolver(hierarchy).solve(problem.posture)
    best = LexicographicSolver(hierarchy).solve(problem.posture)
    assert best.residuals[0] < ACHIEVED_TOLERANCE
    assert best.residuals[1] == pytest.approx(0.1269, abs=5e-4)
    assert result.status == "converged" and result.success
    assert result.residuals[0] < ACHIEVED_TOLERANCE
    assert abs(result.residuals[1] - best.residuals[1]) < 1e-5
    assert set(result.at_limits) == {
        f"{dof}_{side}" for dof in ("knee_flexion", "elbow_flexion") for side in "rl"
    }


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
