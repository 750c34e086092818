"""Passive (ligament and tissue) joint torque models, per DOF (SPEC §2)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import casadi as ca
import numpy as np


class PassiveTorque(Protocol):
    """τp(q_j) [N·m] of one DOF, monotonically decreasing in its angle q_j [rad]: a CasADi
    expression for the torque functions, and numpy values with the slope dτp/dq_j
    [N·m/rad] for the reduced active torque algorithm (SPEC §6)."""

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


@dataclass(frozen=True)
class NoPassive:
    """No passive torque: the joint is free up to its limits (3DSSPP-style statics)."""

    def expression(self, q: ca.SX) -> ca.SX:
        return ca.SX(0.0)

    def numeric(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        zero = np.zeros_like(np.asarray(q, dtype=float))
        return zero, zero
