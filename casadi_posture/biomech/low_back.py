"""Low-back compression and shear at the lumbar joint (L5/S1) by the static
single-equivalent-muscle model of Chaffin & Andersson (docs/low_back.md).

What counts as above L5/S1: every segment and load carried by the lumbar joint (the DOF
``lumbar_flexion`` and the DOFs after it: trunk, head, arms, the loads in the hands), with
their weights, the loads' forces and pure moments. About the joint centre ``o`` they sum to

    F = Σ f_i                                   [N, world]
    M = Σ (x_i − o) × f_i + Σ M_k               [N·m, world]

The disc's frame is the trunk's (the frame of the last lumbar DOF): ``e_z`` along the spine
(up at the zero posture), ``e_x`` forward, ``e_y`` to the left. The sagittal moment the back
muscles must resist is ``M_s = M·e_y`` (positive: the loads flex the trunk, as the lumbar
flexion torque of biomech/torques.py). One equivalent muscle, parallel to the spine,
carries it: the erector spinae at ``E`` behind the disc when ``M_s > 0``, the rectus
abdominis at ``A`` in front of it when ``M_s < 0``:

    F_m = max(M_s, 0)/E + max(−M_s, 0)/A        [N]
    compression = F_m − F·e_z                   [N, positive pressing the disc]
    shear       = F·e_x                         [N, positive: the upper body pushed forward]
    lateral     = F·e_y                         [N, positive: pushed to the left]

Upright with a load in front, ``F = −W ẑ``: compression = M_s/E + W, shear = 0; flexed by θ,
compression = M_s/E + W cos θ and shear = W sin θ (Chaffin's equations). Left out: the
lateral and twisting moments (asymmetric postures), abdominal pressure, muscle
co-contraction, dynamics. A body without a ``lumbar_flexion`` DOF has no model.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from casadi_posture.biomech.torques import applied_forces
from casadi_posture.body.loads import LOAD_PARAMETERS, Load, pack
from casadi_posture.body.tree import BodyModel
from casadi_posture.data import parameters
from casadi_posture.errors import ProblemError

#: The model's name, to be shown with every number it gives.
MODEL = "single equivalent muscle at L5/S1 (Chaffin & Andersson, Occupational Biomechanics)"

#: The lumbar joint's DOFs, the first one defining the joint.
LUMBAR = ("lumbar_flexion", "lumbar_bending", "lumbar_rotation")

#: The outputs of the CasADi function, in order [N, N, N, N·m, N].
OUTPUTS = ("compression", "shear", "lateral_shear", "sagittal_moment", "muscle_force")


@dataclass(frozen=True)
class LowBack:
    """The low-back loads at one posture: ``compression``, ``shear`` (forward +),
    ``lateral_shear`` (left +), the ``muscle_force`` [N] and the ``sagittal_moment`` [N·m]
    (flexing +) it balances."""

    compression: float
    shear: float
    lateral_shear: float
    sagittal_moment: float
    muscle_force: float


def has_lumbar_joint(body: BodyModel) -> bool:
    """Whether ``body`` has the lumbar joint the model needs (a ``lumbar_flexion`` DOF)."""
    return LUMBAR[0] in body.index


def _trunk_frame(body: BodyModel) -> str:
    """The last lumbar DOF of the chain from ``lumbar_flexion``: its frame is the trunk's."""
    frame = LUMBAR[0]
    for name in LUMBAR[1:]:
        if name in body.index and frame in body.ancestors(name):
            frame = name
    return frame


def _above(body: BodyModel, dof: str | None) -> bool:
    """Whether a point carried by ``dof`` is moved by the lumbar joint (lies above L5/S1)."""
    return dof is not None and LUMBAR[0] in body.ancestors(dof)


def low_back_expressions(
    body: BodyModel,
    loads: Sequence[Load],
    p: ca.SX,
    extensor_arm: float | ca.SX,
    flexor_arm: float | ca.SX,
) -> ca.SX:
    """The ``OUTPUTS`` as a column of expressions of ``body.q``, the load vector ``p``
    (``pack``) and the muscles' moment arms [m] (numbers or symbols)."""
    if not has_lumbar_joint(body):
        raise ProblemError(
            None,
            "body",
            body.name,
            f"a body with a lumbar joint ({LUMBAR[0]}) for the low-back model",
        )
    lumbar = body.dofs[body.index[LUMBAR[0]]]
    origin = body.point(lumbar.name, lumbar.origin)
    forces, moments, frames = applied_forces(body, [load.at for load in loads], p)
    carriers = [s.dof for s in body.segments] + [body.landmarks[load.at].dof for load in loads]
    force = ca.SX.zeros(3)
    moment = ca.SX.zeros(3)
    for (point, f), dof in zip(forces, carriers, strict=True):
        if _above(body, dof):
            force += f
            moment += ca.cross(point - origin, f)
    for m, dof in zip(moments, frames, strict=True):
        if _above(body, dof):
            moment += m
    trunk = body.rotation(_trunk_frame(body))
    ex, ey, ez = trunk[:, 0], trunk[:, 1], trunk[:, 2]
    sagittal = ca.dot(moment, ey)
    muscle = ca.fmax(sagittal, 0.0) / extensor_arm + ca.fmax(-sagittal, 0.0) / flexor_arm
    compression = muscle - ca.dot(force, ez)
    return ca.vertcat(compression, ca.dot(force, ex), ca.dot(force, ey), sagittal, muscle)


class LowBackModel:
    """The low-back function of one body with its loads, built once:
    ``function(q, loads) -> (compression, shear, lateral_shear, sagittal_moment,
    muscle_force)``, ``loads`` packed as for the torque model (``pack``)."""

    def __init__(self, body: BodyModel, loads: Sequence[Load]) -> None:
        self.body = body
        self.loads = tuple(loads)
        self.extensor_arm, self.flexor_arm = moment_arms()
        p = ca.SX.sym("loads", LOAD_PARAMETERS * len(self.loads))
        out = low_back_expressions(body, self.loads, p, self.extensor_arm, self.flexor_arm)
        self.function = ca.Function(
            "low_back",
            [body.q, p],
            [out[i] for i in range(len(OUTPUTS))],
            ["q", "loads"],
            list(OUTPUTS),
        )
        self.default_loads = pack(self.loads)

    def evaluate(self, q: Sequence[float], loads: np.ndarray | None = None) -> LowBack:
        """The low-back loads at posture ``q`` [rad]; ``loads`` defaults to the model's own."""
        p = self.default_loads if loads is None else loads
        out = self.function(q=np.asarray(q, dtype=float), loads=p)
        return LowBack(*(float(out[name]) for name in OUTPUTS))


def low_back_model(body: BodyModel, loads: Sequence[Load]) -> LowBackModel | None:
    """The low-back model of ``body`` with ``loads``, or ``None`` for a body without a
    lumbar joint (its compression is not computed, never zero)."""
    return LowBackModel(body, loads) if has_lumbar_joint(body) else None


def moment_arms() -> tuple[float, float]:
    """The erector spinae's and the rectus abdominis's moment arms about L5/S1 [m]."""
    return (
        parameters.value("low_back", "extensor_moment_arm"),
        parameters.value("low_back", "flexor_moment_arm"),
    )


def limits() -> dict[str, float]:
    """The NIOSH compression limits [N]: ``design`` (3400) and ``upper`` (6400)."""
    return {k: parameters.value("low_back", f"limits.{k}") for k in ("design", "upper")}
