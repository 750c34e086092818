"""What both IK solvers return, and the hard constraints active at a posture."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.ik.hierarchy import Inequality

#: A joint within this of a limit [rad], or an inequality within this of its bound, is reported
#: active (an interior-point solver stops about 1e-8 rad inside an active bound).
ACTIVE_TOLERANCE = 1e-6

#: A priority level is achieved when its residual is at most this [m or rad]: 0.1 mm, or
#: 0.006°, far below what a posture study can tell apart, and far above both solvers'
#: convergence (1e-8).
ACHIEVED_TOLERANCE = 1e-4


@dataclass(frozen=True)
class IKResult:
    """A posture from an IK solver.

    ``q`` [rad]; ``residuals`` ‖e_k‖ per priority level (task units);
    ``iterations`` solver iterations in all (IPOPT iterations summed over the
    levels for the lexicographic solver); ``status`` the solver's own word (IPOPT's, or
    the nullspace solver's ``converged``, ``max_iterations``, ``stalled`` or ``stalled:
    level k at a saddle, residual r``: at rest missing a level it could lower);
    ``success`` False whenever the solver failed or a re-check did not pass;
    ``subproblems`` the NLPs solved (lexicographic; 0 for the nullspace solver).
    """

    solver: str
    q: np.ndarray
    residuals: np.ndarray
    iterations: int
    status: str
    success: bool
    at_limits: tuple[str, ...]
    inequality_active: bool
    wall_time_s: float
    subproblems: int = 0

    @property
    def achieved(self) -> tuple[bool, ...]:
        """Per priority level, whether its residual is within ``ACHIEVED_TOLERANCE``."""
        return tuple(bool(r <= ACHIEVED_TOLERANCE) for r in self.residuals)


def active_constraints(
    body: BodyModel, q: np.ndarray, inequality: Inequality | None
) -> tuple[tuple[str, ...], bool]:
    """The DOFs at a joint limit and whether aᵀq ≤ b is active, at posture ``q``."""
    at_limits = tuple(
        d.name
        for i, d in enumerate(body.dofs)
        if q[i] <= d.lower + ACTIVE_TOLERANCE or q[i] >= d.upper - ACTIVE_TOLERANCE
    )
    active = inequality is not None and float(inequality.a @ q) >= inequality.b - ACTIVE_TOLERANCE
    return at_limits, active
