"""The fatigue-reducing constraint (paper §5; docs/model.md): hysteresis per half-joint, one owner,
and the hyperplane aᵀq ≤ b that moves the owner's joint toward a less tiring angle.

While half-joint ``l`` owns the constraint, each step:

    Δq_l = clamp(β·(θg - θc), ±Δq_max)                θg from the reduced active torque algorithm
    Δq_j = α·∂h/∂q_j,  h = τe_l(q)²,  α < 0            the other joints reduce the external torque
    a = -Δq/‖Δq‖,  b = aᵀ(q + Δq)                      (paper eqs 9-11)

The current posture violates aᵀq ≤ b by ‖Δq‖; the IK solvers move it across. Near
the goal the owner's step shrinks and the direction of Δq is no longer meaningful (the α
term takes over); once the owner's step is below ``HOLD_FRACTION`` of Δq_max the plane is
held: the last direction, through the current posture moved by the owner's step alone,
so neither lower tasks nor the α term move the owner back before it recovers (with the α
term's direction instead, the owner sprang back from its goal to the lower task's posture
and out again; with the α term in the offset, the plane drifted a little every step and
took the top task with it).

The plane asks for a step of ‖Δq‖ towards the goal and bounds it on one side only. When
the tasks below would carry the posture farther than that, of their own accord (the goal
lies on the way to their own optimum: after the owner's torque changed sign, case 1.3, the
comfort level swung a seated worker's shoulder 85° back to its tiring start in one second
and the load rose from 0 to 21 %MVC every minute while the constraint stayed on), the
posture solved under the plane lies beyond it by more than Δq_max (``overshot``): the step
is solved again with the plane's sides swapped, aᵀq ≥ b, which lets the posture move the
asked step and no farther (the plane held from then on is the swapped one). The owner
then moves towards its goal at the pace β and Δq_max set, whichever side the other tasks
pull it to.

When the algorithm keeps the owner's angle (no angle of its joint carries less active torque,
"kept θc") and the α term has no direction, no plane is built: the goal is still reported,
and the step keeps its posture.

The whole-body adjustment (``adjustment = "whole_body"``, adjustment/whole_body.py) replaces
the goal angle by the owner's load: its effort weights and its load bound come from there,
with the same hysteresis and owner.

The compatible constraint (our extension; ``keep_levels = N``): in the paper's
experiment the subjects rest while keeping the wrist on the line, but the constraint,
above every task, may break it. With N > 0, Δq is first projected onto the nullspace of
the Jacobians of priority levels 1..N at the current posture (joints at a limit held),
so the constraint moves the posture only in directions the kept tasks allow. When the
projection leaves less than ``BLOCKED_FRACTION`` of the owner's step, the goal cannot be
reached while the kept tasks hold: the constraint is blocked (an event).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from casadi_posture.adjustment.reduced_torque import Goal, JointState, Strategy, goal_angle
from casadi_posture.adjustment.whole_body import WholeBodyAdjustment
from casadi_posture.biomech.passive import PassiveTorque
from casadi_posture.biomech.torques import Torques
from casadi_posture.body.tree import BodyModel
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.result import ACTIVE_TOLERANCE

#: Steps shorter than this fraction of Δq_max keep the previous hyperplane direction.
HOLD_FRACTION = 0.05

#: A projected owner step below this fraction of the unprojected one is blocked.
BLOCKED_FRACTION = 0.1

#: Singular values of the kept levels' Jacobian below this (relative) are no direction.
RANK_TOLERANCE = 1e-9

EventKind = Literal[
    "fatigue_threshold",
    "recovery_threshold",
    "constraint_on",
    "constraint_off",
    "task_not_held",
    "over_strength",
    "exhausted",
    "solver_fallback",
    "constraint_blocked",
    "no_reduction",
    "interrupted",
]

#: The two fatigue adjustments: the paper's goal angle of the owner's joint, or the owner's
#: load lowered over the whole body.
Adjustment = Literal["paper", "whole_body"]


@dataclass(frozen=True)
class ConstraintSettings:
    """Thresholds (fatigue levels), strategy, R_min, ε_τ [N·m], β, Δq_max [rad], α
    [rad/(N·m)²] of the fatigue-reducing constraint, the priority levels it keeps, the
    ``adjustment`` and the whole-body adjustment's fatigue weight k."""

    fatigue_threshold: float = 0.8
    recovery_threshold: float = 0.5
    strategy: Strategy = "active"
    r_min: float = 0.9
    epsilon: float = 0.05
    beta: float = 0.5
    max_step: float = math.radians(1.0)
    alpha: float = -1e-4
    keep_levels: int = 0
    adjustment: Adjustment = "paper"
    fatigue_weight: float = 10.0

    def describe(self) -> str:
        """The adjustment in words: 'active strategy' (the paper's), or the whole body's."""
        if self.adjustment == "whole_body":
            kept = f"levels 1-{self.keep_levels} kept" if self.keep_levels else "levels kept"
            return (
                f"whole-body adjustment ({kept}, effort weighed by 1 + {self.fatigue_weight:g}·F)"
            )
        return f"{self.strategy} strategy"


@dataclass(frozen=True)
class Event:
    """Something that happened at ``time_s`` [s] to a half-joint (or the task)."""

    time_s: float
    kind: EventKind
    half_joint: str
    detail: str = ""


@dataclass
class FatigueConstraint:
    """Hysteresis states of every half-joint and the one constraint they may own."""

    body: BodyModel
    passive: dict[str, PassiveTorque]
    settings: ConstraintSettings
    hierarchy: TaskHierarchy | None = None
    whole_body: WholeBodyAdjustment | None = None
    fatigued: np.ndarray = field(init=False)
    owner: int | None = field(init=False, default=None)
    blocked: bool = field(init=False, default=False)
    _crossed_at: np.ndarray = field(init=False)
    _direction: np.ndarray | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        count = len(self.body.half_joints)
        self.fatigued = np.zeros(count, dtype=bool)
        self._crossed_at = np.full(count, np.inf)

    def update(self, levels: np.ndarray, time_s: float) -> list[Event]:
        """Apply the hysteresis to the fatigue ``levels`` and hand over the constraint."""
        s, names = self.settings, [h.name for h in self.body.half_joints]
        events = []
        for k in np.flatnonzero(~self.fatigued & (levels >= s.fatigue_threshold)):
            self.fatigued[k], self._crossed_at[k] = True, time_s
            events.append(Event(time_s, "fatigue_threshold", names[k], f"fatigue {levels[k]:.3f}"))
        for k in np.flatnonzero(self.fatigued & (levels <= s.recovery_threshold)):
            self.fatigued[k], self._crossed_at[k] = False, np.inf
            events.append(Event(time_s, "recovery_threshold", names[k], f"fatigue {levels[k]:.3f}"))
        if self.owner is not None and not self.fatigued[self.owner]:
            events.append(Event(time_s, "constraint_off", names[self.owner]))
            self.owner, self._direction, self.blocked = None, None, False
        if self.owner is None and self.fatigued.any():
            self.owner = int(np.argmin(self._crossed_at))
            events.append(
                Event(time_s, "constraint_on", names[self.owner], self._acting(self.owner))
            )
        return events

    def _acting(self, owner: int) -> str:
        """What acts on the ``owner``: the paper's strategy on its joint (``passive strategy
        on shoulder_flexion_r``), or the whole-body adjustment, which uses no strategy."""
        if self.whole_body is not None:
            return f"{self.settings.describe()}: its load bounded"
        return f"{self.settings.strategy} strategy on {self.body.half_joints[owner].dof}"

    def hyperplane(
        self, q: np.ndarray, torques: Torques, levels: np.ndarray | None = None
    ) -> tuple[Inequality | None, Goal] | None:
        """The constraint aᵀq ≤ b for the next step (None: the posture stays) and the goal
        (the owner's goal angle; under the whole-body adjustment the owner's load bound, each
        group's effort weighed by its fatigue ``levels``, the goal angle the current one);
        None without an owner."""
        if self.whole_body is not None:
            self.whole_body.weigh(None if self.owner is None else levels)
        if self.owner is None:
            return None
        if self.whole_body is not None:
            return self._whole_body(q)
        s = self.settings
        j = self.body.half_joints[self.owner].dof_index
        dof = self.body.dofs[j]
        curve = self.passive[dof.name].numeric
        joint = JointState(
            float(q[j]),
            float(torques.external[j]),
            float(torques.external_jacobian[j, j]),
            lambda theta: curve(theta)[0],
            lambda theta: curve(theta)[1],
            dof.lower,
            dof.upper,
        )
        goal = goal_angle(joint, s.strategy, r_min=s.r_min, epsilon=s.epsilon)
        dq = s.alpha * 2.0 * torques.external[j] * torques.external_jacobian[j]
        dq[j] = np.clip(s.beta * (goal.angle - q[j]), -s.max_step, s.max_step)
        if s.keep_levels > 0:
            owner_step = abs(dq[j])
            dq = self._kept(q) @ dq
            self.blocked = owner_step > 0 and abs(dq[j]) < BLOCKED_FRACTION * owner_step
        held = np.zeros_like(dq)
        held[j] = dq[j]
        return self._plane(q, dq, abs(dq[j]), held), goal

    def overshot(self, inequality: Inequality, q: np.ndarray) -> Inequality | None:
        """The paper's plane with its sides swapped, −aᵀq ≤ −b, when the posture ``q``
        [rad] solved under ``inequality`` lies beyond it by more than Δq_max (the other
        tasks carried it past the asked step); else None, and always None under the
        whole-body adjustment (its bound is a load, not a step)."""
        if self.whole_body is not None:
            return None
        if inequality.b - float(inequality.a @ q) <= self.settings.max_step:
            return None
        return Inequality(-inequality.a, -inequality.b)

    def hold(self, inequality: Inequality) -> None:
        """``inequality`` was the step's plane (a swapped one): the plane held from now on
        keeps its direction."""
        if self.whole_body is None:
            self._direction = inequality.a

    def _whole_body(self, q: np.ndarray) -> tuple[Inequality | None, Goal]:
        """The whole-body adjustment's load bound (whole_body.py) and what it does."""
        assert self.whole_body is not None and self.owner is not None
        inequality, load = self.whole_body.bound(q, self.owner)
        half = self.body.half_joints[self.owner]
        case = (
            f"whole body: {half.name} at most {load:.2f} %MVC, effort weighed by fatigue, "
            f"levels 1-{self.whole_body.kept} kept"
        )
        return inequality, Goal(float(q[half.dof_index]), case, ())

    def _plane(
        self, q: np.ndarray, dq: np.ndarray, step: float, held: np.ndarray
    ) -> Inequality | None:
        """a = -Δq/‖Δq‖, b = aᵀ(q + Δq) when the ``step`` [rad] that measures Δq is at least
        ``HOLD_FRACTION`` of Δq_max; else the last plane's direction through q + ``held``
        (None when there is none)."""
        norm = float(np.linalg.norm(dq))
        if step >= HOLD_FRACTION * self.settings.max_step and norm > 0:
            self._direction = -dq / norm
            return Inequality(self._direction, float(self._direction @ (q + dq)))
        if self._direction is None:
            return None
        return Inequality(self._direction, float(self._direction @ (q + held)))

    def _kept(self, q: np.ndarray) -> np.ndarray:
        """Projector onto the joint motions that leave levels 1..keep_levels unchanged to first
        order, joints at a limit held."""
        h = self.hierarchy
        if h is None:
            raise ValueError("keep_levels needs the task hierarchy")
        free = np.array(
            [
                d.lower + ACTIVE_TOLERANCE < q[i] < d.upper - ACTIVE_TOLERANCE
                for i, d in enumerate(self.body.dofs)
            ],
            dtype=float,
        )
        values = h.function(q, h.targets)
        kept = min(self.settings.keep_levels, h.depth)
        jacobian = np.vstack([np.asarray(values[h.depth + k]) for k in range(kept)]) * free
        _, sigma, vt = np.linalg.svd(jacobian, full_matrices=False)
        rows = vt[sigma > RANK_TOLERANCE * max(1.0, float(sigma.max(initial=0.0)))]
        return np.diag(free) - rows.T @ rows
