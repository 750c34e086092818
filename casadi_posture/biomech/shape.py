"""A body's person-to-person numbers — joint centres, segment masses and centres of mass,
landmarks, soles and each group's strength — in one fixed order, and a body whose numbers
are CasADi symbols, so that what is built on it (the task hierarchy, the torque model, the
solvers) serves every person of the same structure: scaling to another stature, mass, age
or strength changes numbers, not structure (docs/population.md).

A number that is zero on the body it is built from (a joint centre on the midline, a
segment without lateral offset) stays an exact zero: it is zero on every body of the same
structure, and a symbol there would add instructions to every evaluation. So a shape
serves the bodies whose zeros lie at the same places (``Shape.fits``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from casadi_posture.biomech.strength import ConstantStrength, ScaledCurveStrength, Strength
from casadi_posture.body.tree import BodyModel


def numbers(body: BodyModel, strength: Mapping[str, Strength]) -> np.ndarray:
    """The body's numbers in a fixed order: DOF origins, segment masses and centres of mass,
    landmarks, sole points [m, kg], then each half-joint's constant strength or shipped
    curve's value [N·m] (0 for a curve of a file's own, which is not a number of the body)."""
    out: list[float] = []
    for dof in body.dofs:
        out += dof.origin
    for segment in body.segments:
        out += [segment.mass, *segment.com]
    for landmark in body.landmarks.values():
        out += landmark.position
    for foot in body.feet:
        out += [c for point in foot.outline for c in point]
    for half in body.half_joints:
        model = strength[half.name]
        out.append(model.value if scalable(model) else 0.0)
    return np.asarray(out, dtype=float)


def scalable(model: Strength) -> bool:
    """Whether a strength model is a number times a shape of its own (a constant, or a
    shipped curve's value)."""
    return isinstance(model, ConstantStrength | ScaledCurveStrength)


def rebuilt(body: BodyModel, values: Sequence[float | ca.SX]) -> BodyModel:
    """``body`` with its geometry (the order of ``numbers``, strengths left out) replaced by
    ``values``."""
    it = iter(values)

    def take(n: int) -> tuple[float | ca.SX, ...]:
        return tuple(next(it) for _ in range(n))

    dofs = [replace(d, origin=take(3)) for d in body.dofs]
    segments = []
    for s in body.segments:
        mass, com = take(1)[0], take(3)
        segments.append(replace(s, mass=mass, com=com))
    landmarks = [replace(lm, position=take(3)) for lm in body.landmarks.values()]
    feet = [replace(f, outline=tuple(take(3) for _ in f.outline)) for f in body.feet]
    return BodyModel(body.name, dofs, segments, landmarks, gravity=body.gravity, feet=feet)


@dataclass(frozen=True)
class Shape:
    """The nonzero entries of ``numbers`` as the symbol vector ``symbols``, the body rebuilt
    on them (``body``) and each half-joint's strength with its value a symbol
    (``strength``; a curve of a file's own as it is)."""

    symbols: ca.SX
    nonzero: np.ndarray
    size: int
    body: BodyModel
    strength: dict[str, Strength]

    @classmethod
    def of(cls, body: BodyModel, strength: Mapping[str, Strength]) -> Shape:
        """The shape of ``body`` with ``strength`` per half-joint."""
        values = numbers(body, strength)
        nonzero = np.flatnonzero(values != 0.0)
        symbols = ca.SX.sym("shape", nonzero.size)
        entries: list[float | ca.SX] = [0.0] * values.size
        for k, i in enumerate(nonzero):
            entries[i] = symbols[k]
        groups = len(body.half_joints)
        template = rebuilt(body, entries[: values.size - groups])
        strengths = dict(strength)
        for half, value in zip(body.half_joints, entries[values.size - groups :], strict=True):
            model = strength[half.name]
            if scalable(model):
                strengths[half.name] = replace(model, value=value)  # type: ignore[type-var]
        return cls(symbols, nonzero, values.size, template, strengths)

    def fits(self, values: np.ndarray) -> bool:
        """Whether a body's ``numbers`` have their zeros where this shape's do."""
        return values.size == self.size and np.array_equal(np.flatnonzero(values), self.nonzero)

    def values(self, body: BodyModel, strength: Mapping[str, Strength]) -> np.ndarray:
        """The symbols' values for ``body`` with ``strength`` (which ``fits`` this shape)."""
        values = numbers(body, strength)
        if not self.fits(values):
            raise ValueError(f"body {body.name!r}: its zeros are not where the shape's are")
        return values[self.nonzero]
