"""The reduced active torque algorithm, case by case (paper Table 1), and its properties.

Hand-built configuration: the exponential passive torque
τp = exp(-10θ) - exp(-8(2.2 - θ)) on [-0.2, 2.6] rad, and external-torque lines
τe(θ) = c + s·θ. With s = 2 N·m/rad the slopes match at θs_min = ln(5)/10 ≈ 0.161
and θs_max = 2.2 - ln(4)/8 ≈ 2.027; the extrapolated τa at them is -(c + 0.522)
and -(c + 3.804), so -3.804 < c < -0.522 gives a sign change between them.
Every expected goal below is computed independently (closed form or a dense
scan of the extrapolated τa), not by the module's own dichotomy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from casadi_posture.adjustment.reduced_torque import JointState, dichotomy, goal_angle, slope_angles

LOWER, UPPER = -0.2, 2.6
EPS = 0.05


def passive(theta):
    return np.exp(-10 * np.asarray(theta)) - np.exp(-8 * (2.2 - np.asarray(theta)))


def passive_slope(theta):
    return -10 * np.exp(-10 * np.asarray(theta)) - 8 * np.exp(-8 * (2.2 - np.asarray(theta)))


def joint(angle: float, c: float, slope: float = 2.0, tau_p=passive, dtau_p=passive_slope):
    """Joint l at θc = ``angle`` under the external line τe(θ) = c + slope·θ."""
    return JointState(angle, c + slope * angle, slope, tau_p, dtau_p, LOWER, UPPER)


def zeros_on(j: JointState, lo: float, hi: float) -> list[float]:
    """Zeros of the extrapolated τa on [lo, hi] by a dense scan (independent of the module)."""
    theta = np.linspace(lo, hi, 200_001)
    values = j.active(theta)
    crossings = np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) <= 0)
    return [float(theta[k]) for k in crossings]


S_MIN = math.log(5) / 10
S_MAX = 2.2 - math.log(4) / 8
SCAN = 2 * (UPPER - LOWER) / 200_000


def test_slopes_match_the_closed_form() -> None:
    slopes = slope_angles(joint(1.0, 0.0))
    assert slopes[0] == pytest.approx(S_MIN, abs=1e-4)
    assert slopes[1] == pytest.approx(S_MAX, abs=1e-4)
    assert slope_angles(joint(1.0, 0.0, slope=-1.0)) == ()


# --- no slope (dτe = -1 N·m/rad: τa increases everywhere) -------------------------------


def test_case_1_1_already_at_zero() -> None:
    j = JointState(1.0, -float(passive(1.0)), -1.0, passive, passive_slope, LOWER, UPPER)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert (goal.case, goal.angle) == ("1.1", 1.0)


def test_case_1_2_positive_torque_searches_below() -> None:
    j = JointState(1.0, -1.0, -1.0, passive, passive_slope, LOWER, UPPER)
    (expected,) = zeros_on(j, LOWER, 1.0)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "1.2"
    assert goal.angle == pytest.approx(expected, abs=SCAN)
    assert goal.angle < 1.0


def test_case_1_3_negative_torque_searches_above() -> None:
    j = JointState(1.0, 1.0, -1.0, passive, passive_slope, LOWER, UPPER)
    (expected,) = zeros_on(j, 1.0, UPPER)
    goal = goal_angle(j, "passive", r_min=0.9, epsilon=EPS)
    assert goal.case == "1.3"
    assert goal.angle == pytest.approx(expected, abs=SCAN)
    assert goal.angle > 1.0


def test_case_1_3_with_zeros_on_both_sides_searches_above_first() -> None:
    """Only the upper-limit passive term, τp = -exp(-8(2.2 - θ)), under τe = -1 + 2θ: one
    slope angle (2.2 - ln(4)/8, a minimum of τa), τa(1.5) = -2.0 and both range ends
    positive, so a zero lies on each side of θc. Case 1.3 searches above θc first."""

    def upper_only(theta):
        return -np.exp(-8 * (2.2 - np.asarray(theta)))

    def upper_only_slope(theta):
        return -8 * np.exp(-8 * (2.2 - np.asarray(theta)))

    j = joint(1.5, -1.0, tau_p=upper_only, dtau_p=upper_only_slope)
    assert len(slope_angles(j)) == 1
    (below,) = zeros_on(j, LOWER, 1.5)
    (above,) = zeros_on(j, 1.5, UPPER)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "1.3"
    assert goal.angle == pytest.approx(above, abs=SCAN)
    assert below < 1.5 < goal.angle


def test_case_1_2_with_zeros_on_both_sides_searches_below_first() -> None:
    """The mirror image: only the lower-limit term, τp = exp(-10θ), under τe = -3 + 2θ: one
    slope angle (ln(5)/10, a maximum of τa), τa(1.0) = 1.0 and both range ends negative.
    Case 1.2 searches below θc first."""

    def lower_only(theta):
        return np.exp(-10 * np.asarray(theta))

    def lower_only_slope(theta):
        return -10 * np.exp(-10 * np.asarray(theta))

    j = joint(1.0, -3.0, tau_p=lower_only, dtau_p=lower_only_slope)
    assert len(slope_angles(j)) == 1
    (below,) = zeros_on(j, LOWER, 1.0)
    (above,) = zeros_on(j, 1.0, UPPER)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "1.2"
    assert goal.angle == pytest.approx(below, abs=SCAN)
    assert goal.angle < 1.0 < above


def test_never_worse_than_staying_is_labelled() -> None:
    """Case 3.3 (dτe = 1, τe(0) = -4, θc = -0.15): the extrapolated τa changes sign, but not
    between the slope angles, so the dichotomy there returns the end with the smaller |τa|,
    which is still larger than at θc. The goal stays at θc and the case says why."""
    j = joint(-0.15, -4.0, slope=1.0)
    s_min, s_max = slope_angles(j)
    assert not zeros_on(j, s_min, s_max)
    ends = min(abs(float(j.active(s_min))), abs(float(j.active(s_max))))
    assert ends > abs(float(j.active(-0.15)))
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.angle == -0.15 and goal.case == "3.3 (kept θc: no reduction)"


def test_case_1_2_with_a_decreasing_active_torque_searches_the_other_side() -> None:
    """No passive torque and dτe = 2: τa = 3 - 2θ decreases; its zero 1.5 lies above θc."""

    def zero(theta):
        return 0.0 * np.asarray(theta)

    j = JointState(1.0, -1.0, 2.0, zero, zero, LOWER, UPPER)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "1.2"
    assert goal.angle == pytest.approx(1.5, abs=1e-9)


# --- two slopes, |τa| < ε (already at a zero) -------------------------------------------


def test_case_2_1_between_the_slopes() -> None:
    goal = goal_angle(joint(1.0, -2.0), "passive", r_min=0.9, epsilon=EPS)
    assert (goal.case, goal.angle) == ("2.1", 1.0)


def test_case_2_1_outside_with_both_slope_torques_of_one_sign() -> None:
    (theta_c,) = zeros_on(joint(2.4, 0.0), S_MAX, UPPER)
    goal = goal_angle(joint(theta_c, 0.0), "active", r_min=0.9, epsilon=EPS)
    assert (goal.case, goal.angle) == ("2.1", theta_c)


def test_case_2_2_active_strategy_moves_to_the_mid_range_zero() -> None:
    (theta_c,) = zeros_on(joint(2.4, -2.0), S_MAX, UPPER)
    j = joint(theta_c, -2.0)
    (mid,) = zeros_on(j, S_MIN, S_MAX)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "2.2"
    assert goal.angle == pytest.approx(mid, abs=SCAN)
    assert goal.angle == pytest.approx(1.0, abs=1e-3)


def test_case_2_3_passive_strategy_stays_at_the_passive_zero() -> None:
    (theta_c,) = zeros_on(joint(2.4, -2.0), S_MAX, UPPER)
    goal = goal_angle(joint(theta_c, -2.0), "passive", r_min=0.9, epsilon=EPS)
    assert (goal.case, goal.angle) == ("2.3", theta_c)


# --- two slopes, |τa| > ε --------------------------------------------------------------


def test_case_3_1_active_accepts_the_local_minimum_when_the_ratio_suffices() -> None:
    """c = 0: τa < 0 at θc = 1.5 and at both slopes; |τa| is smallest at θs_min; R ≈ 0.83."""
    j = joint(1.5, 0.0)
    ratio = 1 - float(j.active(S_MIN)) / float(j.active(1.5))
    assert ratio == pytest.approx(0.826, abs=0.005)
    goal = goal_angle(j, "active", r_min=0.5, epsilon=EPS)
    assert goal.case == "3.1"
    assert goal.angle == pytest.approx(S_MIN, abs=1e-4)


def test_case_3_2_a_ratio_below_r_min_takes_the_passive_zero_near_a_limit() -> None:
    j = joint(1.5, 0.0)
    (expected,) = zeros_on(j, S_MAX, UPPER)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "3.2"
    assert goal.angle == pytest.approx(expected, abs=SCAN)
    assert goal.angle > S_MAX


def test_case_3_2_passive_strategy_with_positive_torque_searches_below_s_min() -> None:
    """c = -5: τa > 0 at θc = 1.0 and at both slopes; DSS = Dichotomy(θmin, θs_min)."""
    j = joint(1.0, -5.0)
    assert j.active(1.0) > 0 and j.active(S_MIN) > 0 and j.active(S_MAX) > 0
    (expected,) = zeros_on(j, LOWER, S_MIN)
    goal = goal_angle(j, "passive", r_min=0.0, epsilon=EPS)
    assert goal.case == "3.2"
    assert goal.angle == pytest.approx(expected, abs=SCAN)


def test_case_3_3_active_strategy_finds_the_mid_range_zero() -> None:
    j = joint(1.5, -2.0)
    (mid,) = zeros_on(j, S_MIN, S_MAX)
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert goal.case == "3.3"
    assert goal.angle == pytest.approx(mid, abs=SCAN)


@pytest.mark.parametrize(
    ("theta_c", "lo", "hi"),
    [
        (0.05, LOWER, S_MIN),  # τa > 0, θc < θs_max: below θs_min
        (2.5, S_MAX, UPPER),  # τa > 0, θc ≥ θs_max: above θs_max
        (1.5, S_MAX, UPPER),  # τa < 0, θc > θs_min: above θs_max
        (-0.15, LOWER, S_MIN),  # τa < 0, θc ≤ θs_min: below θs_min
    ],
    ids=["positive-below", "positive-above", "negative-above", "negative-below"],
)
def test_case_3_4_passive_strategy_finds_the_zero_on_its_side(theta_c, lo, hi) -> None:
    j = joint(theta_c, -2.0)
    (expected,) = zeros_on(j, lo, hi)
    goal = goal_angle(j, "passive", r_min=0.9, epsilon=EPS)
    assert goal.case == "3.4"
    assert goal.angle == pytest.approx(expected, abs=SCAN)


def test_dichotomy_without_sign_change_returns_the_smaller_end() -> None:
    j = joint(1.5, 0.0)
    assert dichotomy(j, 0.5, 1.5) == 0.5
    assert dichotomy(j, S_MIN, S_MAX) == S_MIN


# --- properties over random monotone passive curves and external lines -----------------


@st.composite
def configurations(draw):
    k1 = draw(st.floats(0.1, 5.0))
    k2 = draw(st.floats(2.0, 30.0))
    k3 = draw(st.floats(0.1, 5.0))
    k4 = draw(st.floats(2.0, 30.0))
    q1 = draw(st.floats(-0.3, 0.3))
    q2 = draw(st.floats(1.8, 2.4))

    def tau_p(theta):
        theta = np.asarray(theta)
        return k1 * np.exp(-k2 * (theta - q1)) - k3 * np.exp(-k4 * (q2 - theta))

    def dtau_p(theta):
        theta = np.asarray(theta)
        return -k1 * k2 * np.exp(-k2 * (theta - q1)) - k3 * k4 * np.exp(-k4 * (q2 - theta))

    angle = draw(st.floats(LOWER, UPPER))
    external = draw(st.floats(-20.0, 20.0))
    slope = draw(st.floats(-20.0, 20.0))
    return JointState(angle, external, slope, tau_p, dtau_p, LOWER, UPPER)


@settings(max_examples=150, deadline=None)
@given(configurations(), st.sampled_from(["active", "passive"]), st.floats(0.0, 1.0))
def test_goal_stays_in_range_and_never_raises_the_active_torque(j, strategy, r_min) -> None:
    goal = goal_angle(j, strategy, r_min=r_min, epsilon=EPS)
    assert LOWER <= goal.angle <= UPPER
    assert abs(float(j.active(goal.angle))) <= abs(float(j.active(j.angle))) + 1e-9


@settings(max_examples=150, deadline=None)
@given(configurations())
def test_active_strategy_prefers_a_mid_range_zero(j) -> None:
    """Whenever the extrapolated τa has a zero between the slopes (mid-range) and one near a
    limit, and θc is not already at a zero, the active strategy goes to the mid-range one."""
    slopes = slope_angles(j)
    if len(slopes) < 2 or abs(float(j.active(j.angle))) < EPS:
        return
    mid = zeros_on(j, *slopes)
    near_limit = zeros_on(j, LOWER, slopes[0]) + zeros_on(j, slopes[1], UPPER)
    if not mid or not near_limit:
        return
    goal = goal_angle(j, "active", r_min=0.9, epsilon=EPS)
    assert slopes[0] <= goal.angle <= slopes[1]
    assert abs(float(j.active(goal.angle))) < 1e-6
