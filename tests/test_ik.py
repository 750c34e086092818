"""Both IK solvers: analytic solutions, strict priority, limits, the inequality, unreachable
targets, a 3-D chain; and each against the other."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from conftest import PROBLEMS, chain_3d

from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.lexicographic import LexicographicOptions, LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceOptions, NullspaceSolver
from casadi_posture.ik.tasks import JointReference, Line, Plane, Position
from casadi_posture.problem import load_problem

SOLVERS = [NullspaceSolver, LexicographicSolver]
START = np.radians([40.0, 30.0])
L1, L2 = 0.2817, 0.2689


def _arm():
    return load_problem(PROBLEMS / "holding_m45.toml").body


def _wrist(body, q):
    return np.asarray(ca.Function("w", [body.q], [body.landmark("wrist")])(q)).ravel()


def _two_link(x: float, z: float) -> np.ndarray:
    """Analytic sagittal-arm angles (elbow flexed) putting the wrist at (x, z) [rad]."""
    elbow = math.acos((x * x + z * z - L1 * L1 - L2 * L2) / (2 * L1 * L2))
    shoulder = math.atan2(x, -z) - math.atan2(L2 * math.sin(elbow), L1 + L2 * math.cos(elbow))
    return np.array([shoulder, elbow])


@pytest.mark.parametrize("solver", SOLVERS, ids=lambda s: s.name)
def test_line_and_plane_meet_at_the_analytic_intersection(solver) -> None:
    body = _arm()
    angle = math.radians(-25)
    line = Line("line", 1, "wrist", (0.35, 0.0, -0.25), (math.cos(angle), 0.0, math.sin(angle)))
    plane = Plane("plane", 2, "wrist", (0.30, 0.0, 0.0), (1.0, 0.0, 0.0))
    x = 0.30
    z = -0.25 + (x - 0.35) * math.tan(angle)
    result = solver(TaskHierarchy(body, [line, plane])).solve(START)
    assert result.success, result.status
    assert _wrist(body, result.q) == pytest.approx([x, 0.0, z], abs=1e-6)
    assert result.q == pytest.approx(_two_link(x, z), abs=1e-6)


@pytest.mark.parametrize("solver", SOLVERS, ids=lambda s: s.name)
def test_a_conflicting_lower_task_leaves_the_higher_residuals_unchanged(solver) -> None:
    body = _arm()
    line = Line("line", 1, "wrist", (0.35, 0.0, -0.25), (1.0, 0.0, -1.0))
    plane = Plane("plane", 2, "wrist", (0.32, 0.0, 0.0), (1.0, 0.0, 0.0))
    far = Position("far", 3, "wrist", (0.1, 0.0, 0.3))
    alone = solver(TaskHierarchy(body, [line, plane])).solve(START)
    both = solver(TaskHierarchy(body, [line, plane, far])).solve(START)
    assert both.residuals[:2] == pytest.approx(alone.residuals, abs=1e-8)
    assert both.residuals[2] > 0.1
    single = solver(TaskHierarchy(body, [line])).solve(START)
    above = solver(TaskHierarchy(body, [line, far.__class__("far", 2, "wrist", far.target)]))
    assert above.solve(START).residuals[0] == pytest.approx(single.residuals[0], abs=1e-8)


@pytest.mark.parametrize("solver", SOLVERS, ids=lambda s: s.name)
def test_joint_limits_are_never_exceeded(solver, tmp_path) -> None:
    text = (
        (PROBLEMS / "holding_m45.toml")
        .read_text()
        .replace(
            "[posture_deg]", "[body.dofs.elbow_flexion]\nrange_deg = [0.0, 60.0]\n\n[posture_deg]"
        )
        .replace("elbow_flexion = 77.2878", "elbow_flexion = 30.0")
    )
    path = tmp_path / "limited.toml"
    path.write_text(text)
    body = load_problem(path).body
    reach = Position("close", 1, "wrist", (0.15, 0.0, -0.15))
    hierarchy = TaskHierarchy(body, [reach])
    for start in (START, np.radians([-50.0, 59.0]), np.radians([170.0, 0.0])):
        result = solver(hierarchy).solve(start)
        assert np.all(result.q >= body.lower - 1e-9) and np.all(result.q <= body.upper + 1e-9)
        if result.status == "stalled":
            # From (-50°, 59°) the clamping loop comes to rest at both limits, (-60°, 60°),
            # farther from the target than where it started: that is no answer, and the
            # solver must say so and return the best posture it passed.
            assert result.residuals[0] <= hierarchy.residual_norms(start)[0]
            continue
        assert result.success and "elbow_flexion" in result.at_limits


@pytest.mark.parametrize("solver", SOLVERS, ids=lambda s: s.name)
def test_an_active_inequality_is_satisfied_and_the_top_task_kept(solver) -> None:
    body = _arm()
    problem = load_problem(PROBLEMS / "line_plane_hysteresis.toml")
    hierarchy = problem.hierarchy()
    inequality = Inequality(np.array([1.0, 0.0]), math.radians(10.0))
    result = solver(hierarchy).solve(START, inequality)
    assert result.success, result.status
    assert inequality.a @ result.q <= inequality.b + 1e-9
    assert result.inequality_active
    assert result.residuals[0] < 1e-7
    assert result.residuals[1] > 0.01
    assert _wrist(body, result.q)[0] != pytest.approx(0.35, abs=1e-3)


@pytest.mark.parametrize("solver", SOLVERS, ids=lambda s: s.name)
def test_an_unreachable_target_ends_at_the_minimum_distance(solver) -> None:
    body = _arm()
    target = np.array([0.9, 0.0, -0.2])
    result = solver(TaskHierarchy(body, [Position("far", 1, "wrist", tuple(target))])).solve(START)
    assert result.residuals[0] == pytest.approx(np.linalg.norm(target) - (L1 + L2), abs=1e-6)
    # The distance is quadratic in the elbow angle near the straight arm, so the angle is
    # only determined to about the square root of the solver tolerance.
    assert result.q == pytest.approx([math.atan2(0.9, 0.2), 0.0], abs=1e-3)


@pytest.mark.parametrize("solver", SOLVERS, ids=lambda s: s.name)
def test_a_3d_chain_with_non_parallel_axes_solves(solver) -> None:
    body = chain_3d()
    goal = np.radians([25.0, -15.0, 30.0, 70.0, 10.0])
    tip = np.asarray(ca.Function("x", [body.q], [body.landmark("tip")])(goal)).ravel()
    tasks = [
        Position("tip", 1, "tip", tuple(tip)),
        JointReference("rest", 2, ("a", "e"), (0.3, 0.1)),
    ]
    result = solver(TaskHierarchy(body, tasks)).solve(np.radians([5.0, 5.0, 5.0, 40.0, 0.0]))
    assert result.success, result.status
    assert result.residuals[0] < 1e-7
    assert result.q[4] == pytest.approx(0.1, abs=1e-6)


def test_both_solvers_agree_on_a_3d_chain() -> None:
    body = chain_3d()
    tip = (0.1, -0.2, -0.45)
    tasks = [
        Position("tip", 1, "tip", tip),
        JointReference("rest", 2, ("a", "b", "e"), (0.3, 0.2, 0.1)),
    ]
    start = np.radians([5.0, 5.0, 5.0, 40.0, 0.0])
    ns = NullspaceSolver(TaskHierarchy(body, tasks)).solve(start)
    lx = LexicographicSolver(TaskHierarchy(body, tasks)).solve(start)
    assert ns.residuals == pytest.approx(lx.residuals, abs=1e-6)
    assert ns.q == pytest.approx(lx.q, abs=1e-5)


def test_failures_carry_the_solver_status() -> None:
    body = _arm()
    hierarchy = TaskHierarchy(body, [Position("p", 1, "wrist", (0.3, 0.0, -0.3))])
    lx = LexicographicSolver(hierarchy, LexicographicOptions(max_iterations=1)).solve(START)
    assert not lx.success and "Maximum_Iterations_Exceeded" in lx.status
    ns = NullspaceSolver(hierarchy, NullspaceOptions(max_iterations=1)).solve(START)
    assert not ns.success and ns.status == "max_iterations"


def test_a_violated_hard_inequality_is_reported_not_accepted() -> None:
    body = _arm()
    hierarchy = TaskHierarchy(body, [Position("p", 1, "wrist", (0.3, 0.0, -0.3))])
    impossible = Inequality(np.array([1.0, 0.0]), math.radians(-70.0))
    for solver in SOLVERS:
        result = solver(hierarchy).solve(START, impossible)
        assert not result.success, solver.name


def test_a_level_never_ends_farther_from_its_task_than_its_feasible_start() -> None:
    """Reproducer: on the line + plane problem, from the posture the fatigue constraint
    released (the wrist 9e-8 m off the line), IPOPT's level 1 wandered along the line's
    solution set and stopped "acceptable" 1e-6 m off it."""
    hierarchy = load_problem(PROBLEMS / "line_plane_hysteresis.toml").hierarchy()
    start = np.radians([-28.87138313, 142.69473871])
    before = hierarchy.residual_norms(start)[0]
    result = LexicographicSolver(hierarchy).solve(start)
    assert result.success, result.status
    assert before < 1e-7
    assert result.residuals[0] <= before


def test_a_subset_of_levels_is_the_hierarchy_of_those_levels() -> None:
    """``TaskHierarchy.subset`` (the whole-body adjustment's kept levels and comfort level,
    on the expressions already built) evaluates as a hierarchy built of those tasks alone,
    on the body's numbers and on its shape (the person's values bound)."""
    from casadi_posture import simulation
    from casadi_posture.problem import load_problem

    problem = load_problem(PROBLEMS / "standing_wall_horizontal.toml")
    whole = problem.hierarchy()
    keep = [0, 1, whole.depth - 1]
    fresh = TaskHierarchy(problem.body, [t for k in keep for t in whole.levels[k]])
    shaped = simulation._built(problem, 2).whole_body.kept_hierarchy
    rng = np.random.default_rng(5)
    for q in rng.uniform(problem.body.lower, problem.body.upper, (4, problem.body.n)):
        want = fresh.function(q, fresh.targets)
        for sub in (whole.subset(keep), shaped):
            assert sub.level_names() == fresh.level_names()
            for got, expected in zip(sub.function(q, sub.targets), want, strict=True):
                np.testing.assert_allclose(np.asarray(got), np.asarray(expected), atol=1e-10)
