"""Torques over one DOF's range with the other DOFs held (paper Fig. 3), and the zeros of τa."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from casadi_posture.biomech.torques import TorqueModel
from casadi_posture.frames import frame

#: A zero of τa is "passive" (tissue near a limit carries the external torque, the paper's
#: passive strategy) when τp there exceeds this share of the largest |τe| over the range;
#: otherwise it is "active" (the external torque itself vanishes, as mid-range in Fig. 3).
PASSIVE_SHARE = 0.05


@dataclass(frozen=True)
class ActiveZero:
    """A posture where the muscles carry nothing: angle [rad], τp = -τe there [N·m]."""

    angle: float
    passive: float
    kind: str


@dataclass(frozen=True)
class TorqueCurve:
    """Sampled torques [N·m] of DOF ``dof`` over ``angles`` [rad]."""

    dof: str
    angles: np.ndarray
    external: np.ndarray
    passive: np.ndarray
    active: np.ndarray
    zeros: tuple[ActiveZero, ...]

    def to_frame(self) -> object:
        """The samples as a pandas DataFrame: the angle [deg] and τe, τp, τa [N·m]."""
        return frame(
            {
                f"{self.dof}_deg": np.degrees(self.angles),
                "external_Nm": self.external,
                "passive_Nm": self.passive,
                "active_Nm": self.active,
            }
        )

    def zeros_frame(self) -> object:
        """The zeros of τa as a pandas DataFrame: angle [deg], τp = -τe there [N·m], and
        what balances the joint (active: τe ≈ 0; passive: τp carries τe)."""
        return frame(
            {
                "angle_deg": [float(np.degrees(z.angle)) for z in self.zeros],
                "passive_Nm": [z.passive for z in self.zeros],
                "kind": [z.kind for z in self.zeros],
            }
        )


def torque_curve(torques: TorqueModel, q: np.ndarray, dof: str, samples: int = 1001) -> TorqueCurve:
    """Sample τe, τp, τa of ``dof`` over its range at posture ``q`` [rad], in one compiled call."""
    body = torques.body
    j = body.index[dof]
    angles = np.linspace(body.lower[j], body.upper[j], samples)
    postures = np.repeat(np.asarray(q, dtype=float)[:, None], samples, axis=1)
    postures[j] = angles
    loads = np.repeat(torques.default_loads[:, None], samples, axis=1)
    batch = torques.function.map(samples)
    tau_e, tau_p, tau_a = (np.asarray(v)[j] for v in batch(postures, loads)[:3])

    def active(angle: float) -> float:
        posture = np.array(q, dtype=float)
        posture[j] = angle
        return float(torques.function(posture, torques.default_loads)[2][j])

    scale = max(float(np.max(np.abs(tau_e))), 1e-12)
    sign = np.sign(tau_a)
    roots = [angles[k] for k in np.flatnonzero(sign == 0)]
    roots += [
        _bisect(active, angles[k], angles[k + 1]) for k in np.flatnonzero(sign[:-1] * sign[1:] < 0)
    ]
    zeros = []
    for angle in sorted(roots):
        posture = np.array(q, dtype=float)
        posture[j] = angle
        passive = float(torques.function(posture, torques.default_loads)[1][j])
        kind = (
            "passive: τp carries τe" if abs(passive) > PASSIVE_SHARE * scale else "active: τe ≈ 0"
        )
        zeros.append(ActiveZero(angle, passive, kind))
    return TorqueCurve(dof, angles, tau_e, tau_p, tau_a, tuple(zeros))


def _bisect(f: Callable[[float], float], lo: float, hi: float, tol: float = 1e-12) -> float:
    """A root of ``f`` on [lo, hi], where f changes sign."""
    f_lo = f(lo)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        f_mid = f(mid)
        if np.sign(f_mid) == np.sign(f_lo):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
