"""Forward kinematics and Jacobians of the kinematic tree."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from conftest import PROBLEMS, chain_3d

from casadi_posture.body.tree import BodyModel, Dof
from casadi_posture.errors import ProblemError
from casadi_posture.problem import load_problem


def _models() -> list[BodyModel]:
    return [
        load_problem(PROBLEMS / "holding_m45.toml").body,
        load_problem(PROBLEMS / "frontal_elbow.toml").body,
        chain_3d(),
    ]


def _random_postures(body: BodyModel, count: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(body.lower, body.upper, size=(count, body.n))


def _fd_jacobian(f: ca.Function, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    columns = []
    for j in range(q.size):
        dq = np.zeros_like(q)
        dq[j] = h
        columns.append((np.asarray(f(q + dq)) - np.asarray(f(q - dq))).reshape(-1) / (2 * h))
    return np.column_stack(columns)


def _expressions(body: BodyModel) -> dict[str, ca.SX]:
    out = {f"landmark {name}": body.landmark(name) for name in body.landmarks}
    out |= {f"com {s.name}": body.segment_com(s) for s in body.segments}
    out["whole-body com"] = body.com()
    return out


@pytest.mark.parametrize("body", _models(), ids=lambda b: b.name)
def test_position_jacobians_match_finite_differences(body: BodyModel) -> None:
    for label, expression in _expressions(body).items():
        f = ca.Function("f", [body.q], [expression])
        jac = ca.Function("J", [body.q], [body.jacobian(expression)])
        for q in _random_postures(body, 5):
            assert np.allclose(np.asarray(jac(q)), _fd_jacobian(f, q), atol=1e-8), label


@pytest.mark.parametrize("body", _models(), ids=lambda b: b.name)
def test_angular_jacobian_matches_finite_differences_of_rotation(body: BodyModel) -> None:
    h = 1e-6
    for frame in [None, *body.dof_names]:
        rot = ca.Function("R", [body.q], [body.rotation(frame)])
        jw = ca.Function("Jw", [body.q], [body.angular_jacobian(frame)])
        for q in _random_postures(body, 4, seed=1):
            r0 = np.asarray(rot(q))
            for j in range(body.n):
                dq = np.zeros(body.n)
                dq[j] = h
                dr = (np.asarray(rot(q + dq)) - np.asarray(rot(q - dq))) / (2 * h)
                skew = dr @ r0.T
                omega = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
                assert np.allclose(np.asarray(jw(q))[:, j], omega, atol=1e-8)


@pytest.mark.parametrize("body", _models(), ids=lambda b: b.name)
def test_rotations_stay_orthonormal(body: BodyModel) -> None:
    for frame in body.dof_names:
        rot = ca.Function("R", [body.q], [body.rotation(frame)])
        for q in _random_postures(body, 5, seed=2):
            r = np.asarray(rot(q))
            assert np.allclose(r.T @ r, np.eye(3), atol=1e-12)
            assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-12)


def test_sagittal_arm_forward_kinematics_by_hand() -> None:
    body = load_problem(PROBLEMS / "holding_m45.toml").body
    upper = body.landmarks["elbow"].position[2] * -1
    fore = -body.landmarks["wrist"].position[2] - upper
    wrist = ca.Function("w", [body.q], [body.landmark("wrist")])
    for qs, qe in _random_postures(body, 10, seed=3):
        expected = [
            upper * np.sin(qs) + fore * np.sin(qs + qe),
            0.0,
            -upper * np.cos(qs) - fore * np.cos(qs + qe),
        ]
        assert np.allclose(np.asarray(wrist([qs, qe])).reshape(-1), expected, atol=1e-14)


def test_sagittal_arm_flexion_raises_the_arm_forward() -> None:
    body = load_problem(PROBLEMS / "holding_m45.toml").body
    wrist = ca.Function("w", [body.q], [body.landmark("wrist")])
    horizontal = np.asarray(wrist([np.pi / 2, 0.0])).reshape(-1)
    assert horizontal[0] > 0.5 and abs(horizontal[2]) < 1e-12
    forearm_up = np.asarray(wrist([np.pi / 2, np.pi / 2])).reshape(-1)
    assert forearm_up[2] > 0.2


def test_whole_body_com_is_the_mass_weighted_mean() -> None:
    body = chain_3d()
    q = _random_postures(body, 1, seed=4)[0]
    coms = [
        np.asarray(ca.Function("c", [body.q], [body.segment_com(s)])(q)).reshape(-1)
        for s in body.segments
    ]
    masses = np.array([s.mass for s in body.segments])
    expected = (masses[:, None] * np.array(coms)).sum(axis=0) / masses.sum()
    got = np.asarray(ca.Function("c", [body.q], [body.com()])(q)).reshape(-1)
    assert np.allclose(got, expected, atol=1e-14)


def test_half_joints_follow_dof_order() -> None:
    body = load_problem(PROBLEMS / "holding_m45.toml").body
    assert [(h.name, h.sign) for h in body.half_joints] == [
        ("shoulder_flexors", 1),
        ("shoulder_extensors", -1),
        ("elbow_flexors", 1),
        ("elbow_extensors", -1),
    ]


@pytest.mark.parametrize(
    ("dofs", "key"),
    [
        ([Dof("b", "a", (0, 0, 0), (0, 1, 0), 0, 1, "p", "n", ("r", "r"))], "body.dofs.b.parent"),
        ([Dof("a", None, (0, 0, 0), (0, 0, 0), 0, 1, "p", "n", ("r", "r"))], "body.dofs.a.axis"),
        (
            [Dof("a", None, (0, 0, 0), (0, 1, 0), 1, 1, "p", "n", ("r", "r"))],
            "body.dofs.a.range_deg",
        ),
    ],
)
def test_malformed_trees_are_rejected(dofs: list[Dof], key: str) -> None:
    with pytest.raises(ProblemError) as error:
        BodyModel("bad", dofs, [], [], gravity=9.81)
    assert error.value.key == key
