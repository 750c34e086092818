"""The reduced active torque algorithm: the goal angle of the fatigued joint (paper Tables 1–2;
docs/model.md).

Only local knowledge of the external torque is used: along joint l,
``τe(θ) ≈ τe + dτe·(θ - θc)``, so the extrapolated active torque is

    τa(θ) = -(τp(θ) + τe + dτe·(θ - θc)).

Slope matching finds the angles where ``dτp(θ) = -dτe``, the extrema of the
extrapolated τa: none, one, or two (``θs_min < θs_max``); τa has a local
maximum at θs_min and a local minimum at θs_max, and decreases between them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

Strategy = Literal["active", "passive"]
Curve = Callable[[np.ndarray], np.ndarray]

#: Grid of the slope search and the tolerance of every root [rad].
SLOPE_GRID = 401
ANGLE_TOLERANCE = 1e-10


@dataclass(frozen=True)
class JointState:
    """What the algorithm knows of joint l at the current angle ``angle`` θc [rad].

    ``external`` τe [N·m] and ``external_slope`` dτe = ∂τe_l/∂q_l [N·m/rad] at θc;
    ``passive`` τp(θ) and ``passive_slope`` dτp(θ), vectorised [N·m, N·m/rad];
    ``lower``/``upper`` the range [rad].
    """

    angle: float
    external: float
    external_slope: float
    passive: Curve
    passive_slope: Curve
    lower: float
    upper: float

    def active(self, theta: np.ndarray | float) -> np.ndarray:
        """The extrapolated active torque τa(θ) [N·m]."""
        theta = np.asarray(theta, dtype=float)
        line = self.external + self.external_slope * (theta - self.angle)
        return -(self.passive(theta) + line)


@dataclass(frozen=True)
class Goal:
    """The goal angle θg [rad], the case of Table 1 that gave it, and the slope angles."""

    angle: float
    case: str
    slopes: tuple[float, ...]


def slope_angles(joint: JointState) -> tuple[float, ...]:
    """Angles in range where dτp(θ) = -dτe, found on a grid and refined by bisection."""
    grid = np.linspace(joint.lower, joint.upper, SLOPE_GRID)

    def mismatch(theta: np.ndarray | float) -> np.ndarray:
        return joint.passive_slope(np.asarray(theta, dtype=float)) + joint.external_slope

    values = mismatch(grid)
    sign = np.sign(values)
    roots = [float(grid[k]) for k in np.flatnonzero(sign == 0)]
    roots += [
        _root(mismatch, grid[k], grid[k + 1]) for k in np.flatnonzero(sign[:-1] * sign[1:] < 0)
    ]
    roots.sort()
    return (roots[0], roots[-1]) if len(roots) > 2 else tuple(roots)


def dichotomy(joint: JointState, lo: float, hi: float) -> float:
    """A zero of the extrapolated τa on [lo, hi] by a bracketing search; without a sign
    change, the end with the smaller |τa|. Never fails and never leaves [lo, hi]."""
    f_lo, f_hi = float(joint.active(lo)), float(joint.active(hi))
    if f_lo == 0.0:
        return lo
    if f_hi == 0.0:
        return hi
    if np.sign(f_lo) == np.sign(f_hi):
        return lo if abs(f_lo) <= abs(f_hi) else hi
    return _root(joint.active, lo, hi)


def goal_angle(joint: JointState, strategy: Strategy, *, r_min: float, epsilon: float) -> Goal:
    """The goal angle of joint l (paper Table 1), never worse than staying at θc.

    ``r_min`` is the minimum acceptable active-torque decrease ratio R_min;
    ``epsilon`` ε_τ [N·m] the tolerance under which τa counts as zero.
    """
    slopes = slope_angles(joint)
    angle, case = _table_1(joint, slopes, strategy, r_min, epsilon)
    if abs(float(joint.active(angle))) > abs(float(joint.active(joint.angle))):
        angle, case = joint.angle, case + " (kept θc: no reduction)"
    return Goal(float(angle), case, slopes)


def _table_1(
    joint: JointState, slopes: tuple[float, ...], strategy: Strategy, r_min: float, epsilon: float
) -> tuple[float, str]:
    c = joint.angle
    ta = float(joint.active(c))
    if len(slopes) < 2:
        if abs(ta) < epsilon:
            return c, "1.1"
        case = "1.2" if ta > epsilon else "1.3"
        return dichotomy(joint, *_opposite_side(joint, ta, case)), case
    s_min, s_max = slopes
    ta_min, ta_max = float(joint.active(s_min)), float(joint.active(s_max))
    if abs(ta) < epsilon:
        outside_same_sign = (c < s_min or c > s_max) and np.sign(ta_min) == np.sign(ta_max)
        if s_min < c < s_max or outside_same_sign:
            return c, "2.1"
        if strategy == "active":
            return dichotomy(joint, s_min, s_max), "2.2"
        return c, "2.3"
    if np.sign(ta) == np.sign(ta_min) == np.sign(ta_max):
        best = s_max if ta > 0 else s_min
        ratio = (ta - float(joint.active(best))) / ta
        if strategy == "active" and ratio > r_min:
            return best, "3.1"
        return dichotomy(joint, *_same_sign_interval(joint, ta, epsilon, slopes)), "3.2"
    if strategy == "active":
        return dichotomy(joint, s_min, s_max), "3.3"
    return dichotomy(joint, *_opposite_sign_interval(joint, ta, epsilon, slopes)), "3.4"


def _opposite_side(joint: JointState, ta: float, case: str) -> tuple[float, float]:
    """Cases 1.2/1.3: the paper assumes τa increases, so 1.2 searches below θc and 1.3
    above. Each searches its own side first, and the other side only when its own end has
    the sign of τa (no zero there) and the other end does not (τa decreases instead)."""
    c = joint.angle
    below, above = (joint.lower, c), (c, joint.upper)
    own, other = (below, above) if case == "1.2" else (above, below)
    own_end, other_end = (
        (joint.lower, joint.upper)
        if case == "1.2"
        else (
            joint.upper,
            joint.lower,
        )
    )
    sign = np.sign(ta)
    if np.sign(float(joint.active(own_end))) != sign:
        return own
    if np.sign(float(joint.active(other_end))) != sign:
        return other
    return own


def _same_sign_interval(
    joint: JointState, ta: float, epsilon: float, slopes: tuple[float, ...]
) -> tuple[float, float]:
    """SameSignMinandMax (Table 2), the interval of DSS: the passive zero near a limit."""
    s_min, s_max = slopes
    return (joint.lower, s_min) if ta > epsilon else (s_max, joint.upper)


def _opposite_sign_interval(
    joint: JointState, ta: float, epsilon: float, slopes: tuple[float, ...]
) -> tuple[float, float]:
    """OppoSignMinandMax (Table 2), the interval of DOS: the zero on θc's side of the
    mid-range, near a limit."""
    s_min, s_max = slopes
    c = joint.angle
    if ta > epsilon:
        return (joint.lower, s_min) if c < s_max else (s_max, joint.upper)
    return (s_max, joint.upper) if c > s_min else (joint.lower, s_min)


def _root(f: Callable[[float], float | np.ndarray], lo: float, hi: float) -> float:
    """A root of ``f`` on [lo, hi], where f changes sign: regula falsi with the Illinois
    modification (the bracket is kept, as in bisection, and convergence is superlinear)."""
    f_lo, f_hi = float(f(lo)), float(f(hi))
    side = 0
    while hi - lo > ANGLE_TOLERANCE:
        mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        mid = min(max(mid, lo), hi)
        f_mid = float(f(mid))
        if f_mid == 0.0:
            return mid
        if np.sign(f_mid) == np.sign(f_lo):
            lo, f_lo = mid, f_mid
            f_hi = f_hi / 2 if side == -1 else f_hi
            side = -1
        else:
            hi, f_hi = mid, f_mid
            f_lo = f_lo / 2 if side == 1 else f_lo
            side = 1
        if abs(f_mid) < 1e-14:
            return mid
    return 0.5 * (lo + hi)
