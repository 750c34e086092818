"""External, passive and active joint torques and half-joint loads (paper eqs 1–5; docs/model.md).

All torques are about the joint axis, positive in the direction of increasing
angle. External torque by virtual work, ``τe = Σ Jᵀ(m g) + Σ Jᵀ f + Σ J_ωᵀ M``, with the
floor's reaction on a standing body's second foot among the forces (body/support.py);
static equilibrium ``τa + τp + τe = 0`` gives the active torque ``τa = -(τp + τe)``.
When ``τa_j > 0`` the positive half-joint of DOF j carries it, otherwise the
negative one; its load is ``T_N = 100·|τa|/st`` [%MVC].
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache, partial

import casadi as ca
import numpy as np

from casadi_posture.biomech.passive import PassiveTorque
from casadi_posture.biomech.strength import Strength, comfort_strength
from casadi_posture.body.loads import LOAD_PARAMETERS, Load, pack
from casadi_posture.body.support import carried_foot, floor_pressure, reaction_torque
from casadi_posture.body.tree import BodyModel
from casadi_posture.compiled import Compiled


@dataclass(frozen=True)
class Torques:
    """Torques at one posture; per DOF arrays [N·m], per half-joint arrays in
    ``BodyModel.half_joints`` order (positive group of each DOF first), and
    ``external_jacobian[i, j] = ∂τe_i/∂q_j`` [N·m/rad] (paper eq. 12) by AD, computed at
    its first use by ``jacobian_of`` (only the paper's strategy reads it: its compiled
    function has nine tenths of the instructions at 29 DOF)."""

    q: np.ndarray
    external: np.ndarray
    passive: np.ndarray
    active: np.ndarray
    strength: np.ndarray
    half_joint_torque: np.ndarray
    jacobian_of: Callable[[], np.ndarray] = field(repr=False, compare=False)

    @cached_property
    def external_jacobian(self) -> np.ndarray:
        """∂τe_i/∂q_j [N·m/rad] at ``q`` (paper eq. 12)."""
        return self.jacobian_of()

    @property
    def load_pct_mvc(self) -> np.ndarray:
        """Normalised torque T_N of every half-joint [%MVC] (paper eq. 1, in percent)."""
        return 100.0 * self.half_joint_torque / self.strength


#: The array fields of ``Torques``.
_ARRAYS = ("q", "external", "passive", "active", "strength", "half_joint_torque")


class TorqueModel:
    """The torque functions of one body with its loads, compiled once.

    ``function(q, loads) -> (tau_ext, tau_pas, tau_act, strength, dtau_ext)`` with ``loads``
    the vector of ``casadi_posture.loads.pack``, so load masses and forces
    can change without rebuilding anything.

    On a body whose numbers are the symbols of a ``Shape`` (``shape``: the symbols and their
    values for one person) the symbols follow the loads in ``p`` and their values follow
    them in ``default_loads``; ``rebound`` gives another person's model.
    """

    def __init__(
        self,
        body: BodyModel,
        loads: Sequence[Load],
        passive: Mapping[str, PassiveTorque],
        strength: Mapping[str, Strength],
        shape: tuple[ca.SX, np.ndarray] | None = None,
    ) -> None:
        self.body = body
        self.loads = tuple(loads)
        q = body.q
        own = ca.SX.sym("loads", LOAD_PARAMETERS * len(self.loads))
        symbols, numbers = shape if shape is not None else (ca.SX(0, 1), np.zeros(0))
        self.tau_ext, self.tau_pas, self.tau_act, self.strength = torque_expressions(
            body, self.loads, own, passive, strength
        )
        p = ca.vertcat(own, symbols)
        self.p, self.load_symbols = p, own
        outputs = [self.tau_ext, self.tau_pas, self.tau_act, self.strength]
        outputs.append(ca.jacobian(self.tau_ext, q))
        names = ["tau_ext", "tau_pas", "tau_act", "strength", "dtau_ext"]
        self.function = ca.Function("torques", [q, p], outputs, ["q", "loads"], names)
        self.default_loads = np.concatenate([pack(self.loads), numbers])
        self._own = own.numel()
        dense = [ca.densify(v) for v in outputs]  # the expressions, not a call of function
        self._last: tuple[tuple[bytes, bytes], Torques] | None = None
        self._compiled = Compiled(
            ca.Function("torques_dense", [q, p], dense[:4], ["q", "loads"], names[:4])
        )
        self._jacobian = Compiled(
            ca.Function("external_jacobian", [q, p], dense[4:], ["q", "loads"], names[4:])
        )

    def evaluate(self, q: Sequence[float], loads: np.ndarray | None = None) -> Torques:
        """All torques at posture ``q`` [rad]; ``loads`` defaults to the model's own. The
        last answer is kept: a hold whose posture and loads do not change (most steps of a
        simulation nothing tires in) gets a copy of it. (One model per thread: it evaluates
        in buffers of its own.)"""
        p = self.default_loads
        if loads is not None:  # the shape's values follow the loads
            p = np.concatenate([loads, p[self._own :]])
        key = (np.asarray(q, dtype=float).tobytes(), np.asarray(p, dtype=float).tobytes())
        if self._last is None or self._last[0] != key:
            self._last = (key, self._evaluate(q, p))
        kept = self._last[1]
        return replace(kept, **{f: np.array(getattr(kept, f)) for f in _ARRAYS})

    def rebound(self, shape: np.ndarray) -> TorqueModel:
        """This compiled model for another person: the values of its shape's symbols (one
        model per thread: the copies share buffers)."""
        other = copy.copy(self)
        other.default_loads = np.concatenate([self.default_loads[: self._own], shape])
        if other.default_loads.size != self.default_loads.size:
            raise ValueError(f"{shape.size} shape values for {self.default_loads.size - self._own}")
        other._last = None
        return other

    def _evaluate(self, q: Sequence[float], p: np.ndarray) -> Torques:
        """The compiled call behind ``evaluate``."""
        out = self._compiled(q=q, loads=p)
        tau_e, tau_p, tau_a, st = (
            out[k].copy() for k in ("tau_ext", "tau_pas", "tau_act", "strength")
        )
        n = self.body.n
        carried = np.empty(2 * n)
        carried[0::2] = np.maximum(tau_a, 0.0)
        carried[1::2] = np.maximum(-tau_a, 0.0)
        at = np.array(q, dtype=float)
        return Torques(
            at, tau_e, tau_p, tau_a, st, carried, partial(self._external_jacobian, at, p)
        )

    def _external_jacobian(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        """∂τe/∂q [N·m/rad] at ``q`` [rad] with the parameters ``p``, n×n."""
        n = self.body.n
        return self._jacobian(q=q, loads=p)["dtau_ext"].reshape((n, n), order="F").copy()


def torque_expressions(
    body: BodyModel,
    loads: Sequence[Load],
    p: ca.SX,
    passive: Mapping[str, PassiveTorque],
    strength: Mapping[str, Strength],
) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """External, passive and active torque per DOF [N·m] and strength per half-joint [N·m]
    as expressions of ``body.q`` and the load vector ``p`` (``pack``); the body's
    geometry and the models' coefficients may be symbols too."""
    q = body.q
    tau_ext = _external(body, loads, p)
    tau_pas = ca.vertcat(*[passive[d.name].expression(q[i]) for i, d in enumerate(body.dofs)])
    st = ca.vertcat(*[strength[h.name].expression(q) for h in body.half_joints])
    return tau_ext, tau_pas, -(tau_pas + tau_ext), st


def comfort_strengths(body: BodyModel, strength: Mapping[str, Strength]) -> ca.SX:
    """Per half-joint the strength [N·m] the comfort measure's effort divides by
    (``comfort_strength``), an expression of ``body.q``."""
    return ca.vertcat(*[comfort_strength(strength[h.name], body.q) for h in body.half_joints])


def applied_forces(
    body: BodyModel, ats: Sequence[str], p: ca.SX
) -> tuple[list[tuple[ca.SX, ca.SX]], list[ca.SX], list[str | None]]:
    """Every applied force (point [m], force [N], world) — the segments' weights, then the
    weight and push of each load, at its landmark of ``ats`` — the loads' pure moments
    [N·m], and the DOF frame each moment acts on."""
    g = ca.DM([0.0, 0.0, -body.gravity])
    forces = [(body.segment_com(s), s.mass * g) for s in body.segments]
    moments = []
    for k, at in enumerate(ats):
        mass = p[LOAD_PARAMETERS * k]
        force = mass * g + p[LOAD_PARAMETERS * k + 1 : LOAD_PARAMETERS * k + 4]
        forces.append((body.landmark(at), force))
        moments.append(p[LOAD_PARAMETERS * k + 4 : LOAD_PARAMETERS * k + 7])
    return forces, moments, [body.landmarks[at].dof for at in ats]


def _external(body: BodyModel, loads: Sequence[Load], p: ca.SX) -> ca.SX:
    """τe = Σ Jᵀ(m g) + Σ Jᵀ f + Σ J_ωᵀ M, the floor's reaction included [N·m].

    Summed down the tree instead of point by point: DOF j carries every force ``f`` at ``x``
    and moment ``M`` of its subtree, so τe_j = a_j · (Σ x × f + Σ M − o_j × Σ f) with its
    world axis a_j and centre o_j, the same sum as Σ (a_j × (x − o_j)) · f, in one term
    per DOF rather than one per DOF and point (a sixth of the instructions of its Jacobian,
    which the comfort level differentiates again, at 29 DOF)."""
    ats = [load.at for load in loads]
    forces, moments, frames = applied_forces(body, ats, p)
    carriers = [s.dof for s in body.segments] + [body.landmarks[at].dof for at in ats]
    force = {d.name: ca.SX.zeros(3) for d in body.dofs}
    moment = {d.name: ca.SX.zeros(3) for d in body.dofs}
    for (point, f), dof in zip(forces, carriers, strict=True):
        if dof is not None:
            force[dof] += f
            moment[dof] += ca.cross(point, f)
    for m, dof in zip(moments, frames, strict=True):
        if dof is not None:
            moment[dof] += m
    for d in reversed(body.dofs):  # children after their parents: sum up the tree
        if d.parent is not None:
            force[d.parent] += force[d.name]
            moment[d.parent] += moment[d.name]
    tau = ca.vertcat(
        *[
            ca.dot(
                body.joint_axis(d.name),
                moment[d.name] - ca.cross(body.joint_centre(d.name), force[d.name]),
            )
            for d in body.dofs
        ]
    )
    return tau + reaction_torque(body, forces, moments)


@lru_cache(maxsize=16)
def footing_function(body: BodyModel, ats: tuple[str, ...]) -> ca.Function | None:
    """``footing(q, loads) -> (c, s)`` of a body standing on two feet with loads at the
    landmarks ``ats``: the centre of pressure ``c`` (x, y) [m] of everything applied
    (weights, loads, pushes; ``loads`` packed by ``pack``) and the carried foot's share
    ``s`` [-] of the floor's reaction (body/support.py); ``None`` otherwise. Built once per
    body and load points."""
    if carried_foot(body) is None:
        return None
    p = ca.SX.sym("loads", LOAD_PARAMETERS * len(ats))
    forces, moments, _ = applied_forces(body, ats, p)
    pressure, share = floor_pressure(body, forces, moments)
    return ca.Function("footing", [body.q, p], [pressure, share], ["q", "loads"], ["c", "s"])
