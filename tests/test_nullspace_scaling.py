"""The numeric nullspace sweep against independent truths: a plain numpy Baerlocher–Boulic
iteration written here (n×n projectors, the clamping loop restarted every iteration), on
random 7-DOF chains; joint limits, their release, a conflicting inequality, the
identity-Jacobian shortcut and the acceleration.

Both drop the singular values of J̃_k below the rank threshold from the damped step too:
kept, a numerically zero one (1e-16) adds s/λ² ≈ 1e-10 of noise per iteration, and plain
iterations then never settle below a 1e-10 rad step."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np
import pytest

from casadi_posture import api
from casadi_posture.body.tree import BodyModel, Dof, Landmark, Segment
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceOptions, NullspaceSolver, _Held
from casadi_posture.ik.tasks import JointReference, Position, Task

DAMPING, RANK, SLACK = 1e-3, 1e-9, 1e-12


def _chain(seed: int, n: int = 7, limit: float = math.pi) -> BodyModel:
    """A serial chain of ``n`` revolute DOFs with random axes and links, limits ±``limit``."""
    rng = np.random.default_rng(seed)
    dofs, segments, origin, parent = [], [], np.zeros(3), None
    for i in range(n):
        axis = rng.normal(size=3)
        link = rng.normal(scale=0.06, size=3) + np.array([0.0, 0.0, -0.12])
        name = f"j{i}"
        dofs.append(
            Dof(name, parent, tuple(origin), tuple(axis / np.linalg.norm(axis)), -limit, limit,
                "shoulder", f"{name}+", f"{name}-")
        )  # fmt: skip
        segments.append(Segment(f"s{i}", name, 1.0, tuple(origin + link / 2), "o", "tip"))
        origin, parent = origin + link, name
    landmarks = [Landmark("o", None, (0.0, 0.0, 0.0)), Landmark("tip", parent, tuple(origin))]
    return BodyModel(f"chain{seed}", dofs, segments, landmarks, gravity=9.81)


def _tip(body: BodyModel, q: np.ndarray) -> tuple[float, float, float]:
    return tuple(np.asarray(ca.Function("tip", [body.q], [body.landmark("tip")])(q)).ravel())


def _hierarchy(body: BodyModel, goal: np.ndarray, rest: np.ndarray) -> TaskHierarchy:
    """Tip at the tip of ``goal`` ▸ every joint at ``rest``."""
    return TaskHierarchy(
        body,
        [
            Position("tip", 1, "tip", _tip(body, goal)),
            JointReference("rest", 2, tuple(body.dof_names), tuple(rest)),
        ],
    )


def _reference_iteration(
    h: TaskHierarchy, q: np.ndarray, inequality: Inequality | None = None
) -> np.ndarray:
    """One Baerlocher & Boulic iteration in plain numpy, from nothing held."""
    out = h.function(q, h.targets)
    levels = []
    for k in range(h.depth):
        e, jac = np.asarray(out[k]).ravel(), np.asarray(ca.densify(out[h.depth + k]))
        dx = np.empty_like(e)
        for task, rows in h.blocks[k]:
            dx[rows] = -e[rows] * min(1.0, task.step_limit / max(np.linalg.norm(e[rows]), 1e-300))
        levels.append((jac, dx, DAMPING))
    lower, upper, n = h.body.lower, h.body.upper, q.size
    low, high, active = np.zeros(n, bool), np.zeros(n, bool), False
    while True:
        projector = np.diag((~(low | high)).astype(float))
        dq = np.where(low, lower - q, 0.0) + np.where(high, upper - q, 0.0)
        hard = [(inequality.a[None, :], [inequality.b - inequality.a @ q], 0.0)] if active else []
        for jac, dx, damping in [*hard, *levels]:
            u, s, vt = np.linalg.svd(jac @ projector, full_matrices=False)
            u, s, vt = u[:, s > RANK], s[s > RANK], vt[s > RANK]  # singular values below
            dq = dq + vt.T @ (s / (s**2 + damping**2) * (u.T @ (dx - jac @ dq)))  # RANK: noise
            projector = projector - vt.T @ vt
        after = q + dq
        more_low = ~(low | high) & (after < lower - SLACK)
        more_high = ~(low | high) & (after > upper + SLACK)
        violated = inequality is not None and not active and inequality.a @ after > inequality.b
        if not (more_low.any() or more_high.any() or violated):
            return np.clip(after, lower, upper)
        low, high, active = low | more_low, high | more_high, active or bool(violated)


def _reference_solve(h: TaskHierarchy, q: np.ndarray, inequality=None) -> np.ndarray:
    """Plain iterations until the step is below 1e-11 rad."""
    for _ in range(5000):
        q_next = _reference_iteration(h, q, inequality)
        if np.max(np.abs(q_next - q)) < 1e-11:
            return q_next
        q = q_next
    raise AssertionError("the reference did not converge")


def _case(
    seed: int, limit: float = math.pi, spread: float = 0.5, start: float = 0.3
) -> tuple[TaskHierarchy, np.ndarray]:
    """A random chain, its hierarchy (rest ``spread`` from the tip's goal posture) and a
    start ``start`` from it [rad]."""
    rng = np.random.default_rng(seed)
    body = _chain(seed, limit=limit)
    goal = rng.uniform(-0.8, 0.8, body.n) * min(limit, 1.0)
    rest = np.clip(goal + rng.uniform(-spread, spread, body.n), -limit, limit)
    q0 = np.clip(goal + rng.uniform(-start, start, body.n), -limit, limit)
    return _hierarchy(body, goal, rest), q0


@pytest.mark.parametrize("seed", range(4))
def test_one_iteration_is_the_plain_numpy_iteration(seed: int) -> None:
    """The sweep (identity last level, nullspace basis, damped step) against n×n projectors,
    also with joints clamped (a narrow range) and with the inequality activated."""
    h, start = _case(seed)
    solver = NullspaceSolver(h)
    assert solver.iteration(start) == pytest.approx(_reference_iteration(h, start), abs=1e-9)
    narrow, _ = _case(seed, limit=0.35)
    corner = np.full(narrow.body.n, 0.35)  # the step pushes some joints beyond the range
    stepped = NullspaceSolver(narrow).iteration(corner)
    reference = _reference_iteration(narrow, corner)
    assert np.isclose(reference, 0.35, atol=1e-12).any()
    assert stepped == pytest.approx(reference, abs=1e-9)
    after = _reference_iteration(h, start)
    a = np.random.default_rng(seed).normal(size=h.body.n)
    a *= np.sign(a @ (after - start)) / np.linalg.norm(a)
    inequality = Inequality(a, float(a @ (start + after) / 2))  # the free step violates it
    stepped = solver.iteration(start, inequality)
    assert stepped == pytest.approx(_reference_iteration(h, start, inequality), abs=1e-9)
    assert a @ stepped == pytest.approx(inequality.b, abs=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_the_posture_and_residuals_are_the_references(seed: int) -> None:
    """Converged from the same start: the lowest level covers every DOF, so the fixed point
    is unique near the start; the acceleration must not move it."""
    h, start = _case(seed)
    result = NullspaceSolver(h).solve(start)
    q = _reference_solve(h, start)
    assert result.success, result.status
    assert result.q == pytest.approx(q, abs=1e-8)
    assert result.residuals == pytest.approx(h.residual_norms(q), abs=1e-9)
    assert result.residuals[0] < 1e-9


def test_a_joint_the_free_answer_takes_out_of_range_ends_at_its_limit() -> None:
    h, start = _case(1)
    free = NullspaceSolver(h).solve(start).q
    joint = int(np.argmax(np.abs(free - start)))
    bound = float(start[joint] + 0.5 * (free[joint] - start[joint]))  # halfway: binding
    dofs = list(h.body.dofs)
    lower, upper = (bound, math.pi) if free[joint] < bound else (-math.pi, bound)
    dofs[joint] = Dof(**{**dofs[joint].__dict__, "lower": lower, "upper": upper})
    body = BodyModel("limited", dofs, h.body.segments, h.body.landmarks.values(), gravity=9.81)
    limited = TaskHierarchy(body, [t for level in h.levels for t in level])
    result = NullspaceSolver(limited).solve(start)
    assert result.success, result.status
    assert result.q[joint] == pytest.approx(bound, abs=1e-12)
    assert result.at_limits == (body.dofs[joint].name,)
    assert result.residuals[0] < 1e-9  # the redundant chain reaches the target without it
    assert result.q == pytest.approx(_reference_solve(limited, start), abs=1e-8)


def test_a_held_joint_is_released_when_the_tasks_pull_it_back() -> None:
    """From a start at the range's corner, the first iteration holds a joint at its limit;
    the solution has every joint inside, so the solve must release it again."""
    body = _chain(3, n=3, limit=0.6)
    goal = np.array([-0.331, -0.211, 0.241])
    h = TaskHierarchy(body, [Position("tip", 1, "tip", _tip(body, goal))])
    start = np.array([0.569, 0.6, -0.6])
    solver = NullspaceSolver(h)
    assert np.isclose(np.abs(solver.iteration(start)), 0.6, atol=1e-12).any()
    result = solver.solve(start)
    assert result.success, result.status
    assert result.at_limits == ()
    assert result.residuals[0] < 1e-9
    assert result.q == pytest.approx(_reference_solve(h, start), abs=1e-8)


def test_a_held_inequality_is_released_when_the_tasks_pull_back_inside() -> None:
    """j2 starts 0.4 rad above its bound, 0.05 rad above where the tasks alone put it: the
    first iteration holds the inequality, moving onto aᵀq = b; the solution is the free
    one, inside, so the inequality must be let go again."""
    h, start = _case(0)
    solver = NullspaceSolver(h)
    free = solver.solve(start).q
    inequality = Inequality(np.eye(h.body.n)[2], float(free[2] + 0.05))
    q0 = free + 0.4 * np.eye(h.body.n)[2]
    assert solver.iteration(q0, inequality)[2] == pytest.approx(inequality.b, abs=1e-12)
    result = solver.solve(q0, inequality)
    assert result.success and not result.inequality_active
    assert result.q == pytest.approx(free, abs=1e-8)


def test_a_conflicting_inequality_stalls_within_the_bound_at_its_best_posture() -> None:
    """Joint j0 held 0.35 rad below the only posture that reaches the target: the
    recursion limit-cycles; it must stop within twice the stall window, say so, and return
    the best posture it passed, which keeps the inequality."""
    body = _chain(4, n=2)
    goal = np.array([0.6, 0.4])
    h = TaskHierarchy(body, [Position("tip", 1, "tip", _tip(body, goal))])
    inequality = Inequality(np.array([1.0, 0.0]), 0.6 - 0.35)
    options = NullspaceOptions()
    result = NullspaceSolver(h, options).solve(goal + 0.05, inequality)
    assert result.status == "stalled" and not result.success
    assert result.iterations <= 2 * options.stall_iterations
    assert inequality.violation(result.q) <= 1e-9
    assert result.residuals[0] > 1e-2


@dataclass(frozen=True)
class _Angles(Task):
    """JointReference's residual under another type: the generic (SVD) path."""

    dofs: tuple[str, ...]
    reference: tuple[float, ...]

    step_limit = JointReference.step_limit

    def targets(self) -> np.ndarray:
        return np.array(self.reference)

    def residual(self, body: BodyModel, p: ca.SX) -> ca.SX:
        return ca.vertcat(*[body.q[body.index[d]] for d in self.dofs]) - p


@pytest.mark.parametrize("order", ["all", "shuffled", "some"])
def test_a_selection_level_equals_the_generic_path(order: str) -> None:
    h, start = _case(3)
    names = list(h.body.dof_names)
    rng = np.random.default_rng(0)
    shuffled = list(rng.permutation(names))
    picked = {"all": names, "shuffled": shuffled, "some": shuffled[:4]}[order]
    rest = tuple(rng.uniform(-0.5, 0.5, len(picked)))
    tip = h.levels[0][0]
    strict = NullspaceOptions(tolerance=1e-10)  # both paths to the same fixed point, closely
    a = NullspaceSolver(
        TaskHierarchy(h.body, [tip, JointReference("r", 2, tuple(picked), rest)]), strict
    )
    b = NullspaceSolver(TaskHierarchy(h.body, [tip, _Angles("r", 2, tuple(picked), rest)]), strict)
    assert a._levels[1].identity == (order != "some") and b._levels[1].jacobian is not None
    assert a.iteration(start) == pytest.approx(b.iteration(start), abs=1e-12)
    assert a.solve(start).q == pytest.approx(b.solve(start).q, abs=1e-10)


@pytest.mark.parametrize("seed", range(3))
def test_the_acceleration_reaches_the_plain_fixed_point_in_fewer_iterations(seed: int) -> None:
    """A rest posture far from the tip's: the plain iteration contracts slowly (60 to 80
    iterations from 0.02 rad); accelerated, it must reach the same posture in half."""
    h, start = _case(seed, spread=1.5, start=0.02)
    strict = NullspaceOptions(tolerance=1e-10)  # the fixed point itself, not a stop near it
    plain = NullspaceSolver(h, replace(strict, acceleration_memory=0)).solve(start)
    fast = NullspaceSolver(h, strict).solve(start)
    assert plain.success and fast.success
    assert fast.q == pytest.approx(plain.q, abs=1e-8)
    assert fast.iterations < plain.iterations / 2


def test_the_compiled_call_is_the_hierarchys_not_an_unrolled_sweep() -> None:
    """Build cost grows with the model, not with passes of the sweep: the one compiled
    output holds the residuals and the Jacobians the sweep needs (none for the joint
    references), and nothing else."""
    h, _ = _case(0)
    assert NullspaceSolver(h)._out.size == sum(h.sizes) + h.sizes[0] * h.body.n


def test_a_rebound_solver_solves_the_other_targets_as_a_new_one() -> None:
    h, start = _case(0)
    other, _ = _case(0, spread=1.0)  # the same chain and tasks, other rest angles
    solver = NullspaceSolver(h)
    rebound = solver.rebind(other)
    assert rebound.solve(start).q == pytest.approx(NullspaceSolver(other).solve(start).q)
    assert solver.solve(start).q == pytest.approx(NullspaceSolver(h).solve(start).q)


#: problems/standing_shelf_box.toml as first written: upright on the legs and the lumbar
#: spine only, so the arms' share of the centre of mass couples them to the legs through
#: the feet and balance task, weakly (singular values of J̃_3 down to 2e-4).
SHELF = """
title = "Standing: a 6 kg box held with both hands at a shelf 1.40 m high, 0.62 m ahead"
[body]
model = "standing"
sex = "male"
stature_m = 1.741
mass_kg = 73.0
[posture_deg]
shoulder_flexion_r = 60.0
shoulder_flexion_l = 60.0
elbow_flexion_r = 30.0
elbow_flexion_l = 30.0
[[loads]]
name = "box_right_half"
at = "grip_r"
mass_kg = 3.0
[[loads]]
name = "box_left_half"
at = "grip_l"
mass_kg = 3.0
[[tasks]]
name = "feet"
kind = "feet"
priority = 1
[[tasks]]
name = "balance"
kind = "com"
axes = "xy"
priority = 1
[[tasks]]
name = "right_hand_at_shelf"
kind = "position"
effector = "grip_r"
priority = 2
target_m = [0.62, -0.15, 1.40]
[[tasks]]
name = "left_hand_at_shelf"
kind = "position"
effector = "grip_l"
priority = 2
target_m = [0.62, 0.15, 1.40]
[[tasks]]
name = "upright"
kind = "posture"
priority = 3
reference_deg = { lumbar_flexion = 0, lumbar_bending = 0, lumbar_rotation = 0, \
hip_flexion_r = 0, hip_abduction_r = 0, hip_rotation_r = 0, knee_flexion_r = 0, \
ankle_flexion_r = 0, ankle_inversion_r = 0, hip_flexion_l = 0, hip_abduction_l = 0, \
hip_rotation_l = 0, knee_flexion_l = 0, ankle_flexion_l = 0, ankle_inversion_l = 0 }
"""


@pytest.fixture(scope="module")
def shelf():
    problem = api.loads(SHELF, "standing_shelf_box")  # the backslashes join the lines
    hierarchy = problem.hierarchy()
    return problem, hierarchy, NullspaceSolver(hierarchy), LexicographicSolver(hierarchy)


@pytest.mark.parametrize("where", ["file", "upright"])
def test_the_standing_shelf_reaches_the_hands_level_as_the_lexicographic_solver(
    shelf, where: str
) -> None:
    """The 29-DOF standing body, the box at the shelf. The plain damped step (λ = 1e-3)
    took the posture level's nearly singular directions at up to 500 times its error: 1 rad
    of shoulder rotation at the second iteration, the feet and balance task broken at second
    order, joints thrown to their limits; the solve stalled at the start posture, 0.275 m
    from the shelf (from upright with the arms hanging, 1.28 m). The damping floor keeps the
    fixed point and reaches it. The lexicographic solver ends 2e-5 rad lower on the posture
    level, paying 3e-6 m on level 1 (measured with the earlier de Leva limb lengths, where
    IPOPT with both upper levels held exactly at zero gave 0.0896193 rad against the
    Gauss-Newton fixed point's 0.0896401: a direction reachable at second order only)."""
    problem, _, ns, lx = shelf
    body = problem.body
    upright = np.clip(np.zeros(body.n), body.lower, body.upper)
    start = problem.posture if where == "file" else upright
    a, b = ns.solve(start), lx.solve(start)
    assert a.success, a.status
    assert a.residuals[0] < 1e-9 and a.residuals[1] < 1e-9
    # IPOPT from upright: near the level, not exact (2.9e-5 to 1.02e-4 m across installs)
    assert b.residuals[0] < 1e-5 and b.residuals[1] < 2e-4
    assert a.residuals[2] == pytest.approx(b.residuals[2], abs=1e-4)
    assert a.residuals[2] == pytest.approx(0.239177, abs=1e-5)
    assert a.iterations < 100


def test_the_floor_leaves_the_fixed_point_alone(shelf) -> None:
    """With the joints the solve ends at held there (the elbows, straight), the paper's
    sweep without the floor does not move the posture: the floor changes the path only.
    (Up to 4e-8 rad: the solve, asked for a 1e-10 rad step here, stops there, and the
    paper's gains are up to 500 times larger along the weak directions.)"""
    problem, hierarchy, _, _ = shelf
    result = NullspaceSolver(hierarchy, NullspaceOptions(tolerance=1e-10)).solve(problem.posture)
    assert result.at_limits
    q, body = result.q, problem.body
    side = np.zeros(body.n, dtype=int)
    for name in result.at_limits:
        i = body.index[name]
        side[i] = -1 if abs(q[i] - body.lower[i]) < abs(q[i] - body.upper[i]) else 1
    plain = NullspaceSolver(hierarchy, NullspaceOptions(curvature=0.0))
    _, dx = plain._point(q)
    assert np.abs(plain._sweep(q, dx, None, _Held(side, False))).max() < 1e-6
