"""A body's person-to-person numbers as symbols (biomech/shape.py): what is built on them
once serves another person of the same structure, and gives what a build for that person
gives (simulation._built)."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from casadi_posture import simulation
from casadi_posture.adjustment.whole_body import WholeBodyAdjustment
from casadi_posture.biomech.shape import Shape, numbers, rebuilt
from casadi_posture.biomech.torques import TorqueModel
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.tasks import Comfort
from casadi_posture.problem import load_problem
from casadi_posture.simulation import simulate

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
WALL = PROBLEMS / "standing_wall_horizontal.toml"
#: Another worker of the same sex: every number of the body and three strengths changed.
OTHER = {
    "body.stature_m": 1.62,
    "body.mass_kg": 88.5,
    "body.age_years": 51.0,
    "body.half_joints.elbow_flexors_r.strength_scale": 0.8,
    "body.half_joints.shoulder_flexors_r.strength_scale": 1.3,
    "body.half_joints.lumbar_extensors.strength_scale": 0.9,
}


def _random_postures(body, count=5, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(body.lower, body.upper, size=(count, body.n))


def test_a_rebuilt_body_is_the_body() -> None:
    """The body rebuilt from its own numbers places every point where the body does."""
    problem = load_problem(WALL)
    body = problem.body
    values = numbers(body, problem.strength)
    same = rebuilt(body, values[: values.size - len(body.half_joints)].tolist())

    points = [body.com(), *[body.landmark(n) for n in body.landmarks]]
    again = [same.com(), *[same.landmark(n) for n in same.landmarks]]
    f = ca.Function("f", [body.q], [ca.vertcat(*points)])
    g = ca.Function("g", [same.q], [ca.vertcat(*again)])
    for q in _random_postures(body):
        np.testing.assert_allclose(np.asarray(g(q)), np.asarray(f(q)), rtol=0, atol=1e-14)


def test_what_is_built_for_one_person_serves_another() -> None:
    """Levels, Jacobians, torques and the whole-body load bound of the build on worker A's
    shape with worker B's values are those of a build for B, at random postures."""
    a, b = load_problem(WALL), load_problem(WALL, OTHER)
    shape = Shape.of(a.body, a.strength)
    values_b = shape.values(b.body, b.strength)
    assert not np.allclose(values_b, shape.values(a.body, a.strength))
    pair = (shape.symbols, shape.values(a.body, a.strength))
    torques_a = TorqueModel(shape.body, a.loads, a.passive, shape.strength, pair)
    tasks = simulation._shaped(a.task_objects(), shape, a, torques_a)
    assert [t.active is not None for t in tasks if isinstance(t, Comfort)] == [True]  # shared
    template = TaskHierarchy(shape.body, tasks, pair)
    hierarchy = template.rebound(b.task_objects(), values_b)
    torques = torques_a.rebound(values_b)
    fresh = TaskHierarchy(b.body, b.task_objects())
    fresh_torques = b.torque_model()
    bound = WholeBodyAdjustment(torques_a, template, k=0.0, keep_levels=2).rebind(
        hierarchy, k=0.0, torque_model=torques
    )
    fresh_bound = WholeBodyAdjustment(fresh_torques, fresh, k=0.0, keep_levels=2)
    for q in _random_postures(b.body):
        for got, want in zip(
            hierarchy.function(q, hierarchy.targets), fresh.function(q, fresh.targets), strict=True
        ):
            np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-11, atol=1e-11)
        got, want = torques.evaluate(q), fresh_torques.evaluate(q)
        for name in ("external", "passive", "active", "strength", "external_jacobian"):
            np.testing.assert_allclose(
                getattr(got, name), getattr(want, name), rtol=1e-11, atol=1e-9
            )
        elbow = [h.name for h in b.body.half_joints].index("elbow_flexors_r")
        got_bound, got_load = bound.bound(q, elbow)
        want_bound, want_load = fresh_bound.bound(q, elbow)
        assert got_load == pytest.approx(want_load, rel=1e-11)
        np.testing.assert_allclose(got_bound.a, want_bound.a, atol=1e-11)


@pytest.mark.parametrize(("solver", "atol"), [("nullspace", 1e-9), ("lexicographic", 1e-6)])
def test_a_second_worker_reuses_the_build_and_gets_their_own_answer(solver, atol) -> None:
    """Worker B after worker A (one build, rebound) holds as B alone with a build of their
    own: the same events and the same postures (to 1e-9 rad; IPOPT stops at its own
    tolerance)."""
    short = {"simulation.duration_s": 400.0}
    a, b = load_problem(WALL, short), load_problem(WALL, {**short, **OTHER})
    simulation._builds.__dict__.clear()
    expected = simulate(b, solver)
    simulation._builds.__dict__.clear()
    simulate(a, solver)
    again = simulate(b, solver)
    assert len(simulation._builds.kept) == 1
    assert any(e.kind == "constraint_on" for e in again.events)
    assert [(e.time_s, e.kind, e.half_joint) for e in again.events] == [
        (e.time_s, e.kind, e.half_joint) for e in expected.events
    ]
    np.testing.assert_allclose(again.timeline.q, expected.timeline.q, rtol=0, atol=atol)
    np.testing.assert_allclose(again.timeline.load, expected.timeline.load, rtol=0, atol=1e3 * atol)


def test_another_sex_or_strength_model_is_another_structure() -> None:
    """A woman's body (other data) and a strength model of a file's own are built anew."""
    short = {"simulation.duration_s": 5.0}
    simulation._builds.__dict__.clear()
    simulate(load_problem(WALL, short), "nullspace")
    simulate(load_problem(WALL, {**short, "body.sex": "female"}), "nullspace")
    curve = {
        "body.half_joints.elbow_flexors_r.strength_curve": {
            "dof": "elbow_flexion_r",
            "angle_deg": [0.0, 90.0],
            "strength_Nm": [60.0, 70.0],
        }
    }
    simulate(load_problem(WALL, {**short, **curve}), "nullspace")
    assert len(simulation._builds.kept) == 3


def test_a_shape_refuses_a_body_with_its_zeros_elsewhere() -> None:
    problem = load_problem(WALL)
    shape = Shape.of(problem.body, problem.strength)
    values = numbers(problem.body, problem.strength)
    assert shape.fits(values)
    moved = values.copy()
    moved[np.flatnonzero(values == 0.0)[0]] = 0.01
    assert not shape.fits(moved)
