"""The whole-body fatigue adjustment (``fatigue.adjustment = "whole_body"``; docs/comfort.md):
beside the paper's, which moves the tired group's joint to a goal angle (reduced_torque.py),
this one lowers the tired group's load over the whole body.

While half-joint ``l`` owns the constraint (the same hysteresis as the paper's), each step
from the posture q_c [rad] solves the NLP

    min_q  Σ_g c_g (τa_g / st_g)²  +  displacement  +  limits        (the comfort level)
    s.t.   the kept priority levels: 1..keep_levels, or every level above the comfort one
           the joint limits
           T_l(q_c) + ∇T_lᵀ(q − q_c) ≤ T_l(q_c)                      aᵀq ≤ b

with every group's effort weighed by ``c_g = 1 + k·F_g`` (F_g its fatigue level, k the
fatigue weight): the load moves off the tired groups onto fresh ones and the posture stays
as comfortable as that allows; the tired group's load T_l = 100·s_l·τa_j/st_l [%MVC] (s_l
its sign, j its DOF) may not rise above its value at q_c, linearised there (``a = ∇T_l/‖∇T_l‖``,
``b = aᵀq_c``: q_c on the boundary, so the constraint never breaks a kept level), with
∇T_l exact by AD. The NLP is the IK of the kept levels and the weighted comfort level, with
that inequality, solved by the simulation's own solvers; the levels below the kept ones
give way (their residuals are recorded). Released, the weights go back to 1 and the IK to
every level.
"""

from __future__ import annotations

import copy

import casadi as ca
import numpy as np

from casadi_posture.biomech.torques import TorqueModel
from casadi_posture.compiled import Compiled
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.tasks import Comfort

#: A load gradient shorter than this [%MVC/rad] gives no direction to bound.
FLAT_GRADIENT = 1e-9


class WholeBodyAdjustment:
    """The whole-body adjustment of one simulation, built once: the hierarchy of the kept
    levels and the comfort level (``kept_hierarchy``), the compiled half-joint loads and their
    gradients, and where the comfort level's effort weights lie in the targets of both
    hierarchies (set in place, so the solvers bound to them see the weights)."""

    def __init__(
        self, torque_model: TorqueModel, hierarchy: TaskHierarchy, *, k: float, keep_levels: int
    ) -> None:
        body = torque_model.body
        comfort = hierarchy.levels[-1][0]
        if not isinstance(comfort, Comfort) or not comfort.measure.effort:
            raise ValueError("the whole-body adjustment needs a comfort level that counts effort")
        self.kept = keep_levels if 0 < keep_levels < hierarchy.depth else hierarchy.depth - 1
        self.kept_hierarchy = hierarchy.subset([*range(self.kept), hierarchy.depth - 1])
        self._bind(hierarchy, self.kept_hierarchy)
        self.k = k
        signs = np.array([h.sign for h in body.half_joints], dtype=float)
        active = ca.vertcat(*[torque_model.tau_act[h.dof_index] for h in body.half_joints])
        load = 100.0 * ca.DM(signs) * active / torque_model.strength
        # the owner's gradient by one reverse sweep of pickᵀ·load (pick: 1 at the owner), not
        # the whole Jacobian of which it is one row (5 207 instructions instead of 26 472)
        pick = ca.SX.sym("pick", load.numel())
        self._load = Compiled(
            ca.Function(
                "half_joint_load",
                [body.q, torque_model.p, pick],
                [load, ca.densify(ca.gradient(ca.dot(pick, load), body.q))],
                ["q", "loads", "pick"],
                ["load", "gradient"],
            )
        )
        self._pick = np.zeros(load.numel())
        self._packed = torque_model.default_loads

    def _bind(self, hierarchy: TaskHierarchy, kept: TaskHierarchy) -> None:
        """Set the effort weights in the targets of ``hierarchy`` and ``kept`` from now on."""
        comfort = hierarchy.levels[-1][0]
        span = comfort.effort_weights()
        self.kept_hierarchy = kept
        self._weights = [
            (h, slice(h.offset(comfort) + span.start, h.offset(comfort) + span.stop))
            for h in (hierarchy, kept)
        ]

    def rebind(
        self, hierarchy: TaskHierarchy, *, k: float, torque_model: TorqueModel
    ) -> WholeBodyAdjustment:
        """This adjustment, its compiled functions shared, on ``hierarchy`` (the ``rebound``
        of the one it was built on, for this run's person) with its kept levels rebound
        alike, the weight ``k`` and the person's ``torque_model`` (the ``rebound`` of the
        one it was built on)."""
        other = copy.copy(self)
        tasks = [t for level in hierarchy.levels for t in level]
        other._bind(hierarchy, self.kept_hierarchy.rebound(tasks, hierarchy.shape_values()))
        other._packed = torque_model.default_loads
        other.k = k
        return other

    def weigh(self, fatigue: np.ndarray | None) -> None:
        """Weigh each group's effort by 1 + k·F_g (``fatigue`` per half-joint), or by 1 (None)."""
        weights = 1.0 if fatigue is None else 1.0 + self.k * np.asarray(fatigue, dtype=float)
        for hierarchy, where in self._weights:
            hierarchy.targets[where] = weights

    def bound(self, q: np.ndarray, owner: int) -> tuple[Inequality | None, float]:
        """The ``owner`` half-joint's load [%MVC] at ``q`` [rad] and the hard constraint that
        it does not rise, linearised there (None where the load does not depend on q)."""
        self._pick[:] = 0.0
        self._pick[owner] = 1.0
        out = self._load(q=q, loads=self._packed, pick=self._pick)
        value = float(out["load"][owner])
        gradient = out["gradient"].copy()
        norm = float(np.linalg.norm(gradient))
        if norm <= FLAT_GRADIENT:
            return None, value
        a = gradient / norm
        return Inequality(a, float(a @ q)), value
