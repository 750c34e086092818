"""Passive (ligament and tissue) joint torque models, per DOF.

Every model is monotonically decreasing in the joint angle: positive (pushing the
joint up) near its lower limit, negative near its upper limit, about zero mid-range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import casadi as ca
import numpy as np


class PassiveTorque(Protocol):
    """τp(q_j) [N·m] of one DOF, monotonically decreasing in its angle q_j [rad]: a CasADi
    expression for the torque functions, and numpy values with the slope dτp/dq_j
    [N·m/rad] for the reduced active torque algorithm (docs/model.md)."""

    def expression(self, q: ca.SX) -> ca.SX: ...

    def numeric(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class ExponentialPassive:
    """τp = k1·exp(-k2·(q - q1)) - k3·exp(-k4·(q2 - q)) (Riener & Edrich 1999 style).

    k1, k3 [N·m]; k2, k4 [1/rad]; q1, q2 [rad]: the torque is k1 at q1 from the
    lower-limit term and -k3 at q2 from the upper-limit term.
    """

    k1: float
    k2: float
    q1: float
    k3: float
    k4: float
    q2: float

    def expression(self, q: ca.SX) -> ca.SX:
        low = self.k1 * ca.exp(-self.k2 * (q - self.q1))
        return low - self.k3 * ca.exp(-self.k4 * (self.q2 - q))

    def numeric(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        low = self.k1 * np.exp(-self.k2 * (q - self.q1))
        high = self.k3 * np.exp(-self.k4 * (self.q2 - q))
        return low - high, -self.k2 * low - self.k4 * high


def limit_torque(lower: float, upper: float, limit: float, decade: float) -> ExponentialPassive:
    """The limit-torque convention of PredSim: ``limit`` [N·m] at each end of the range
    [``lower``, ``upper``] [rad], growing tenfold over each ``decade`` (a fraction of the
    range) beyond it, about zero mid-range: k2 = k4 = ln 10 / (decade·(upper − lower))."""
    rate = math.log(10.0) / (decade * (upper - lower))
    return ExponentialPassive(limit, rate, lower, limit, rate, upper)


@dataclass(frozen=True)
class ReshapedPassive:
    """A passive curve with the paper's reshaping near both limits (its Figs 15 and 17): "a
    small linear term added on both limits to ensure that passive torque is big enough to
    compensate external torque".

    Within ``width`` [rad] of a limit the torque gains ``step + slope·depth`` [N·m] toward
    the middle of the range, ``depth`` [rad] being how far inside the band the angle is.
    With ``step = 0`` the curve stays continuous (its slope jumps at the band's edge); a
    ``step > 0`` is a jump there, the "sudden change in active torque" the paper reports.
    It stays monotonically decreasing either way.
    """

    base: PassiveTorque
    lower: float
    upper: float
    width: float
    slope: float
    step: float = 0.0

    def expression(self, q: ca.SX) -> ca.SX:
        low_edge, high_edge = self.lower + self.width, self.upper - self.width
        low = ca.if_else(q < low_edge, self.step + self.slope * (low_edge - q), 0.0)
        high = ca.if_else(q > high_edge, self.step + self.slope * (q - high_edge), 0.0)
        return self.base.expression(q) + low - high

    def numeric(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q = np.asarray(q, dtype=float)
        value, slope = self.base.numeric(q)
        low_edge, high_edge = self.lower + self.width, self.upper - self.width
        in_low, in_high = q < low_edge, q > high_edge
        value = value + np.where(in_low, self.step + self.slope * (low_edge - q), 0.0)
        value = value - np.where(in_high, self.step + self.slope * (q - high_edge), 0.0)
        slope = slope - self.slope * (in_low.astype(float) + in_high.astype(float))
        return value, slope


@dataclass(frozen=True)
class NoPassive:
    """No passive torque: the joint is free up to its limits (3DSSPP-style statics)."""

    def expression(self, q: ca.SX) -> ca.SX:
        return ca.SX(0.0)

    def numeric(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        zero = np.zeros_like(np.asarray(q, dtype=float))
        return zero, zero
