"""The evidence that tells a target out of reach from a local minimum: seeded starts within
the joint limits, a chain's reach, the joints held at a bound."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import PROBLEMS

from casadi_posture.ik.reach import at_bounds, beyond_reach, chain, random_starts
from casadi_posture.ik.tasks import Line, Position
from casadi_posture.problem import load_problem

ARM = load_problem(PROBLEMS / "holding_m25.toml").body


def test_random_starts_are_seeded_uniform_within_the_limits() -> None:
    starts = random_starts(ARM, 4000, seed=3)
    assert starts.shape == (4000, 2)
    assert np.all(starts >= ARM.lower) and np.all(starts <= ARM.upper)
    # uniform: each angle's mean and spread are the range's midpoint and range/√12
    span = ARM.upper - ARM.lower
    assert np.allclose(starts.mean(axis=0), (ARM.lower + ARM.upper) / 2, atol=0.03 * span)
    assert np.allclose(starts.std(axis=0), span / math.sqrt(12), rtol=0.03)
    assert np.array_equal(random_starts(ARM, 10, seed=3), starts[:10])
    assert not np.array_equal(random_starts(ARM, 10, seed=4), starts[:10])


def test_chain_of_the_wrist_is_the_upper_arm_and_forearm() -> None:
    root, longest, shortest = chain(ARM, "wrist")
    upper_arm = -ARM.landmarks["elbow"].position[2]
    forearm = ARM.landmarks["elbow"].position[2] - ARM.landmarks["wrist"].position[2]
    assert np.allclose(root, 0.0)
    assert longest == pytest.approx(upper_arm + forearm)
    assert shortest == pytest.approx(upper_arm - forearm)
    assert chain(ARM, "shoulder") is None  # fixed to the world


@pytest.mark.parametrize(
    ("target", "beyond"),
    [((0.35, 0.0, -0.25), False), ((0.35, 0.0, -0.95), True), ((0.0, 0.0, -0.005), True)],
)
def test_a_point_beyond_or_inside_the_chain_is_out_of_reach(target, beyond: bool) -> None:
    why = beyond_reach(ARM, [Position("dot", 1, "wrist", target)])
    assert (why is not None) == beyond
    if beyond:
        distance = math.dist(target, (0.0, 0.0, 0.0))
        assert f"{distance:.3f} m from shoulder_flexion's centre" in why


def test_a_line_out_of_reach_is_its_distance_from_the_shoulder() -> None:
    far = Line("line", 1, "wrist", (0.0, 0.0, -0.8), (1.0, 0.0, 0.0))  # 0.8 m below it
    near = Line("line", 1, "wrist", (5.0, 0.0, -0.3), (1.0, 0.0, 0.0))  # 0.3 m below it
    assert "line is 0.800 m from shoulder_flexion's centre" in beyond_reach(ARM, [far])
    assert beyond_reach(ARM, [near]) is None


def test_at_bounds_names_the_joint_and_its_limit() -> None:
    q = np.array([ARM.upper[0] - 1e-8, ARM.lower[1] + 0.5])
    assert at_bounds(ARM, q) == ["shoulder_flexion at its upper limit, 180°"]
