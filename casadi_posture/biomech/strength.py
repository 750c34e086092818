"""Joint strength: maximum voluntary torque of each half-joint, possibly posture dependent."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import casadi as ca

from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter


class Strength(Protocol):
    """st(q) [N·m] of one half-joint, an expression of the whole joint vector q [rad]."""

    def expression(self, q: ca.SX) -> ca.SX: ...


@dataclass(frozen=True)
class ConstantStrength:
    """A posture-independent strength [N·m]."""

    value: float

    def expression(self, q: ca.SX) -> ca.SX:
        return ca.SX(self.value)


@dataclass(frozen=True)
class TabulatedStrength:
    """Strength interpolated linearly in one DOF's angle, held constant beyond the table.

    ``angles`` [rad] strictly increasing, ``values`` [N·m], ``dof_index`` the
    DOF whose angle it depends on (e.g. 3DSSPP-style curves entered by the user).
    """

    dof_index: int
    angles: tuple[float, ...]
    values: tuple[float, ...]

    def expression(self, q: ca.SX) -> ca.SX:
        angle = ca.fmin(ca.fmax(q[self.dof_index], self.angles[0]), self.angles[-1])
        return ca.pw_lin(angle, ca.DM(self.angles), ca.DM(self.values))


def default_strength(
    half_joint: str, *, sex: str, stature: float, body_mass: float, age: float
) -> tuple[ConstantStrength, Parameter]:
    """The default strength of a half-joint (docs/sources.md) and its provenance.

    Elbow flexors from the Harbo et al. 2012 regression at this stature [m],
    body mass [kg] and age [years]; other groups by the Gymnast strength ratio.
    """
    table = parameters.load("strength")
    ratio = table[f"strength.ratio.{half_joint}"]
    c = {
        k: parameters.value("strength", f"harbo_2012.{sex}.{k}")
        for k in ("intercept", "age", "stature", "body_mass")
    }
    elbow_flexors = (
        c["intercept"] + c["age"] * age + c["stature"] * stature + c["body_mass"] * body_mass
    )
    value = elbow_flexors * ratio.value
    record = Parameter(
        name=f"strength.{half_joint}",
        value=round(value, 4),
        unit="N·m",
        source=(
            f"Harbo 2012 elbow-flexion regression ({sex}, {age:g} y, {stature:g} m, "
            f"{body_mass:g} kg) = {elbow_flexors:.2f} N·m × ratio {ratio.value:g} ({ratio.source})"
        ),
        status="estimate",
        evidence="C1+E",
    )
    return ConstantStrength(value), record


def known_groups() -> Sequence[str]:
    """Half-joints with a shipped default strength."""
    return [
        name.removeprefix("strength.ratio.")
        for name in parameters.load("strength")
        if name.startswith("strength.ratio.")
    ]
