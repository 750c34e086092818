"""Task residuals and their Jacobians (finite differences) on planar and 3-D models."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from conftest import PROBLEMS, chain_3d

from casadi_posture.body.tree import BodyModel
from casadi_posture.ik.hierarchy import TaskHierarchy
from casadi_posture.ik.tasks import (
    CentreOfMass,
    JointReference,
    Line,
    Orientation,
    Plane,
    Position,
    Task,
    rotation_rpy,
)
from casadi_posture.problem import load_problem


def _all_tasks(body: BodyModel, effector: str, segment_dof: str) -> list[Task]:
    r = tuple(rotation_rpy(0.2, -0.4, 0.7).ravel(order="F"))
    return [
        Position("p", 1, effector, (0.3, 0.1, -0.2)),
        Line("l", 2, effector, (0.35, 0.0, -0.25), (0.9, 0.1, -0.42)),
        Plane("pl", 3, effector, (0.3, 0.0, 0.0), (1.0, 0.2, 0.1)),
        Orientation("o", 4, "seg", segment_dof, r),
        CentreOfMass("c", 5, (0.05, 0.0, -0.2), "xz"),
        JointReference("j", 6, (body.dof_names[-1],), (0.4,)),
    ]


@pytest.mark.parametrize(
    ("body", "effector", "dof"),
    [
        (load_problem(PROBLEMS / "holding_m45.toml").body, "wrist", "elbow_flexion"),
        (chain_3d(), "tip", "d"),
    ],
    ids=["sagittal_arm", "chain_3d"],
)
def test_every_task_jacobian_matches_finite_differences(
    body: BodyModel, effector: str, dof: str
) -> None:
    hierarchy = TaskHierarchy(body, _all_tasks(body, effector, dof))
    rng = np.random.default_rng(5)
    h = 1e-6
    for q in rng.uniform(body.lower, body.upper, size=(5, body.n)):
        values = hierarchy.function(q, hierarchy.targets)
        for k in range(hierarchy.depth):
            fd = np.column_stack(
                [
                    (
                        np.asarray(hierarchy.function(q + h * e, hierarchy.targets)[k])
                        - np.asarray(hierarchy.function(q - h * e, hierarchy.targets)[k])
                    ).ravel()
                    / (2 * h)
                    for e in np.eye(body.n)
                ]
            )
            assert np.allclose(np.asarray(values[hierarchy.depth + k]), fd, atol=1e-8), k


def test_residuals_vanish_exactly_when_tasks_hold() -> None:
    body = chain_3d()
    q = np.radians([20, -10, 35, 60, 15])
    tip = np.asarray(ca.Function("x", [body.q], [body.landmark("tip")])(q)).ravel()
    rot = np.asarray(ca.Function("R", [body.q], [body.rotation("d")])(q))
    com = np.asarray(ca.Function("c", [body.q], [body.com()])(q)).ravel()
    tasks = [
        Position("p", 1, "tip", tuple(tip)),
        Line("l", 1, "tip", tuple(tip - 0.3 * np.array([1, 2, 3])), (1.0, 2.0, 3.0)),
        Plane("pl", 1, "tip", tuple(tip + np.array([0.0, 0.4, 0.0])), (1.0, 0.0, 0.0)),
        Orientation("o", 1, "s_d", "d", tuple(rot.ravel(order="F"))),
        CentreOfMass("c", 1, tuple(com), "xyz"),
        JointReference("j", 1, ("b", "d"), (q[1], q[3])),
    ]
    hierarchy = TaskHierarchy(body, tasks)
    assert hierarchy.residual_norms(q)[0] == pytest.approx(0.0, abs=1e-14)


def test_residual_values_by_hand() -> None:
    body = chain_3d()
    q = np.zeros(body.n)
    tip = np.array([0.12, -0.05, -0.60])
    line = Line("l", 1, "tip", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    plane = Plane("pl", 2, "tip", (0.0, 0.0, -0.5), (0.0, 0.0, 2.0))
    angle = 0.3
    orientation = Orientation(
        "o", 3, "s_d", "d", tuple(rotation_rpy(0.0, 0.0, angle).ravel(order="F"))
    )
    values = TaskHierarchy(body, [line, plane, orientation]).function(
        q, np.concatenate([line.targets(), plane.targets(), orientation.targets()])
    )
    assert np.linalg.norm(np.asarray(values[0])) == pytest.approx(math.hypot(*tip[:2]))
    assert float(values[1]) == pytest.approx(tip[2] + 0.5)
    assert np.asarray(values[2]).ravel() == pytest.approx([0.0, 0.0, -math.sin(angle)])
