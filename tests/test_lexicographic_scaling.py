"""The lexicographic solver on redundant chains: level 1 to 1e-8, strict priority at an
active inequality and at a singular posture, an active inequality honoured, no state
carried from one call to the next, and IPOPT taking over when SQP fails."""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from conftest import PROBLEMS

from casadi_posture.body.tree import BodyModel, Dof, Landmark, Segment
from casadi_posture.ik import lexicographic
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.lexicographic import LexicographicOptions, LexicographicSolver
from casadi_posture.ik.tasks import JointReference, Position
from casadi_posture.problem import load_problem

LINK = 0.08  # [m]


def _chain(n: int, seed: int) -> BodyModel:
    """n revolute DOFs in series with random axes, ±150° ranges, a 1 kg segment per link
    of ``LINK`` m and a 'hand' landmark at the tip (straight down at the zero posture)."""
    rng = np.random.default_rng(seed)
    dofs, segments, parent = [], [], None
    for i in range(n):
        axis = rng.normal(size=3)
        name = f"j{i}"
        limit = math.radians(150.0)
        dofs.append(
            Dof(
                name,
                parent,
                (0.0, 0.0, -LINK * i),
                tuple(axis / np.linalg.norm(axis)),
                -limit,
                limit,
                "shoulder",
                f"{name}+",
                f"{name}-",
            )
        )
        segments.append(Segment(f"link{i}", name, 1.0, (0.0, 0.0, -LINK * (i + 0.5)), "a", "b"))
        parent = name
    landmarks = [Landmark("hand", parent, (0.0, 0.0, -LINK * n))]
    return BodyModel(f"chain{n}", dofs, segments, landmarks, gravity=9.81)


def _reach_and_rest(
    n: int, seed: int, postures: int | None = None
) -> tuple[TaskHierarchy, np.ndarray]:
    """On ``_chain(n, seed)``, the hand at a point it reaches in a random posture (level 1),
    every joint toward another random posture (level 2), both drawn with seed
    ``postures`` (default ``seed``); and the first posture [rad]."""
    body = _chain(n, seed)
    rng = np.random.default_rng(100 + (seed if postures is None else postures))
    reaching, rest = rng.uniform(-1.2, 1.2, (2, n))
    hand = ca.Function("hand", [body.q], [body.landmark("hand")])
    target = tuple(np.asarray(hand(reaching)).ravel())
    tasks = [
        Position("reach", 1, "hand", target),
        JointReference("rest", 2, tuple(body.dof_names), tuple(rest)),
    ]
    return TaskHierarchy(body, tasks), reaching


@pytest.mark.parametrize("n", [7, 14])
@pytest.mark.parametrize("seed", [0, 1])
def test_level_one_is_reached_to_1e_8_on_redundant_chains(n: int, seed: int) -> None:
    """The target is reachable by construction; from 8° off every joint (SQP) and from
    the straight chain (IPOPT, then SQP) the hand ends within 1e-8 m of it. IPOPT alone
    left up to 2e-6 m."""
    hierarchy, reaching = _reach_and_rest(n, seed)
    solver = LexicographicSolver(hierarchy)
    signs = np.random.default_rng(seed).choice([-1.0, 1.0], n)
    for start in (reaching + math.radians(8.0) * signs, np.zeros(n)):
        result = solver.solve(start)
        assert result.success, result.status
        assert result.residuals[0] <= 1e-8


def test_a_second_call_answers_as_a_fresh_solver() -> None:
    """Nothing of a call (its inequality, its multipliers, its start) leaks into the next:
    the same posture in as many iterations."""
    hierarchy, _ = _reach_and_rest(7, 2)
    solution = LexicographicSolver(hierarchy).solve(np.zeros(7)).q
    held = Inequality(np.eye(7)[3], float(solution[3] - 0.2))
    used = LexicographicSolver(hierarchy)
    used.solve(np.zeros(7), held)
    start = solution + math.radians(0.5)
    again = used.solve(start)
    fresh = LexicographicSolver(hierarchy).solve(start)
    assert again.success and fresh.success
    np.testing.assert_allclose(again.q, fresh.q, rtol=0.0, atol=1e-12)
    assert again.iterations == fresh.iterations


def test_a_rebound_solver_answers_as_a_fresh_one_on_other_targets() -> None:
    """Rebinding shares the compiled NLPs; the targets and joint ranges are the new ones."""
    hierarchy, _ = _reach_and_rest(7, 7)
    other, reaching = _reach_and_rest(7, 7, postures=8)
    narrow = [replace(d, lower=d.lower / 2, upper=d.upper / 2) for d in other.body.dofs]
    body = BodyModel(
        "narrow", narrow, other.body.segments, other.body.landmarks.values(), gravity=9.81
    )
    other = TaskHierarchy(body, [t for level in other.levels for t in level])
    start = np.clip(reaching + math.radians(8.0), body.lower, body.upper)
    solver = LexicographicSolver(hierarchy)
    solver.solve(np.zeros(7))
    rebound = solver.rebind(other).solve(start)
    fresh = LexicographicSolver(other).solve(start)
    assert rebound.success, rebound.status
    np.testing.assert_allclose(rebound.q, fresh.q, rtol=0.0, atol=1e-12)
    assert np.all(rebound.q <= body.upper + 1e-9) and np.all(rebound.q >= body.lower - 1e-9)


def test_a_lower_level_never_moves_off_the_inequality_at_the_higher_levels_expense() -> None:
    """A step of the -45° hold's simulation: the fatigue inequality keeps the wrist off
    its line. Level 1 alone ends 0.0353 m off it; the line + dot hierarchy must end there
    too (counting the active inequality as fixed dropped the row that leaving it changes,
    and the dot took level 1 to 0.114 m)."""
    hierarchy = load_problem(PROBLEMS / "holding_m45.toml").hierarchy()
    line_alone = TaskHierarchy(hierarchy.body, hierarchy.levels[0])
    start = np.array([-0.167642, 2.617992])
    held = Inequality(np.array([0.956868, -0.290522]), -0.939237)
    alone = LexicographicSolver(line_alone).solve(start, held)
    both = LexicographicSolver(hierarchy).solve(start, held)
    assert alone.success and both.success, (alone.status, both.status)
    assert alone.residuals[0] == pytest.approx(0.0353, abs=1e-4)
    assert both.residuals[0] <= alone.residuals[0] + 1e-8


def test_a_lower_level_never_bends_a_straight_arm_off_its_best_reach() -> None:
    """A point 0.6 m in front of the shoulder, beyond the arm: level 1 ends with the arm
    straight, at the arm's length from it (to IPOPT's accuracy on an unachieved level).
    There the distance changes only at second order, so no row of it is kept; the final
    level must still not bend the arm (it took the wrist 0.214 m from the point)."""
    body = load_problem(PROBLEMS / "holding_m45.toml").body
    at = ca.Function("at", [body.q], [body.landmark("wrist")])
    length = float(np.linalg.norm(np.asarray(at(np.zeros(body.n))).ravel()))
    hierarchy = TaskHierarchy(body, [Position("reach", 1, "wrist", (0.6, 0.0, 0.0))])
    result = LexicographicSolver(hierarchy).solve(np.radians([16.8833, 77.2878]))
    assert result.success, result.status
    assert result.residuals[0] == pytest.approx(0.6 - length, abs=1e-7)


def test_an_active_inequality_is_honoured_and_only_the_lower_level_pays() -> None:
    """One joint held 0.2 rad below where the unconstrained hierarchy puts it: the bound
    holds to 1e-9, the hand still reaches its target, and the rest posture can only get
    worse."""
    hierarchy, reaching = _reach_and_rest(7, 3)
    solver = LexicographicSolver(hierarchy)
    start = reaching + math.radians(8.0)
    free = solver.solve(start)
    held = Inequality(np.eye(7)[2], float(free.q[2] - 0.2))
    result = solver.solve(start, held)
    assert free.success and result.success, (free.status, result.status)
    assert result.q[2] <= held.b + 1e-9
    assert result.inequality_active
    assert result.residuals[0] <= 1e-8
    assert result.residuals[1] >= free.residuals[1] - 1e-9


def test_ipopt_takes_over_when_sqp_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    """SQP allowed one iteration cannot solve level 1 from 8° off: IPOPT does, and the
    answer is the one SQP finds when it may iterate."""
    hierarchy, reaching = _reach_and_rest(7, 4)
    start = reaching + math.radians(8.0)
    reference = LexicographicSolver(hierarchy)
    expected = reference.solve(start)
    monkeypatch.setattr(lexicographic, "SQP_MAX_ITERATIONS", 1)
    hobbled = LexicographicSolver(hierarchy)
    result = hobbled.solve(start)
    assert reference.methods[0] == "sqp"
    assert hobbled.methods[0] in ("ipopt", "ipopt+sqp")
    assert result.success, result.status
    np.testing.assert_allclose(result.residuals, expected.residuals, rtol=0.0, atol=1e-6)


def test_a_far_start_goes_to_ipopt_and_sqp_polishes_its_answer() -> None:
    """From the straight chain the hand is predicted to move more than SQP_RADIUS: IPOPT
    solves level 1 and SQP takes its answer from IPOPT's accuracy to 1e-8 m."""
    hierarchy, _ = _reach_and_rest(7, 5)
    solver = LexicographicSolver(hierarchy)
    result = solver.solve(np.zeros(7))
    assert result.success, result.status
    assert solver.methods[0] == "ipopt+sqp"
    assert result.residuals[0] <= 1e-8


def test_an_iteration_limit_below_sqps_leaves_ipopt_alone() -> None:
    """A limit under SQP_MAX_ITERATIONS is IPOPT's: no SQP solver is built or used."""
    hierarchy, reaching = _reach_and_rest(7, 6)
    limited = LexicographicOptions(max_iterations=lexicographic.SQP_MAX_ITERATIONS - 1)
    solver = LexicographicSolver(hierarchy, limited)
    result = solver.solve(reaching + math.radians(0.5))
    assert all(solver._level(k).sqp is None for k in range(2))
    assert set(solver.methods) == {"ipopt"}
    assert result.success, result.status


def test_a_level_sqp_settles_builds_no_ipopt() -> None:
    """From a start next to the answer SQP settles every level and no IPOPT is built (its
    build is half a cold start's); from the far start IPOPT is built and used."""
    hierarchy, reaching = _reach_and_rest(7, 6)
    far = LexicographicSolver(hierarchy)
    answer = far.solve(reaching)
    assert answer.success, answer.status
    assert any("ipopt" in m for m in far.methods)
    assert any(far._level(k).ipopt is not None for k in range(hierarchy.depth))
    solver = LexicographicSolver(hierarchy)
    near = solver.solve(answer.q + 1e-4)
    assert near.success, near.status
    assert set(solver.methods) == {"sqp"}
    assert all(solver._level(k).ipopt is None for k in range(hierarchy.depth + 1))
    np.testing.assert_allclose(near.q, answer.q, atol=1e-6)


@pytest.mark.parametrize(
    "path",
    [PROBLEMS.parent / "benchmarks/problems/humanoid_14.toml", PROBLEMS / "holding_m45.toml"],
)
def test_the_derivatives_given_to_sqp_are_those_of_its_nlp(path) -> None:
    """Each level's SQP reads its objective's gradient and its constraints' Jacobian from
    the hierarchy's Jacobians and the kept rows' curvature from once-differentiated
    functions: against CasADi's own derivatives of the level's NLP at random postures
    and multipliers, the kept rows' S_j random. The humanoid's level 1 has a
    structurally sparse gradient (8 of 14 entries), which sqpmethod would misread."""
    problem = load_problem(path)
    h = TaskHierarchy(problem.body, problem.task_objects())
    solver = LexicographicSolver(h)
    rng = np.random.default_rng(3)
    for k in range(h.depth + 1):
        level = solver._level(k)
        nlp, given = level.nlp, level.sqp.function
        x, p, g = nlp["x"], nlp["p"], nlp["g"]
        sigma, lam = ca.SX.sym("sigma"), ca.SX.sym("lam", g.numel())
        gauss_newton = (
            2 * h.jacobians[k].T @ h.jacobians[k]
            + lexicographic.REGULARISATION * ca.SX.eye(x.numel())
            if k < h.depth
            else 2 * ca.SX.eye(x.numel())
        )
        own = ca.Function(
            "own",
            [x, p, sigma, lam],
            [
                ca.gradient(nlp["f"], x),
                ca.jacobian(g, x),
                sigma * gauss_newton + ca.hessian(ca.dot(lam, g), x)[0],
            ],
        )
        assert given.get_function("nlp_jac_fg").sparsity_out("grad_f_x").is_dense()
        for _ in range(3):
            q = rng.uniform(problem.body.lower, problem.body.upper)
            kept = [
                np.concatenate([rng.normal(size=(m, m)).ravel("F"), rng.normal(size=m) * 0.01])
                for m in h.sizes[:k]
            ]
            values = np.concatenate([h.targets, q, rng.normal(size=q.size), [1.0], *kept])
            multipliers, weight = rng.normal(size=g.numel()), rng.uniform(0.5, 2.0)
            gradient, jacobian, hessian = (
                np.asarray(v) for v in own(q, values, weight, multipliers)
            )
            _, given_gradient, _, given_jacobian = given.get_function("nlp_jac_fg")(q, values)
            given_hessian = given.get_function("nlp_hess_l")(q, values, weight, multipliers)
            np.testing.assert_allclose(
                np.asarray(given_gradient).ravel(), gradient.ravel(), atol=1e-10
            )
            np.testing.assert_allclose(np.asarray(given_jacobian), jacobian, atol=1e-10)
            np.testing.assert_allclose(np.asarray(given_hessian), hessian, atol=1e-9)
