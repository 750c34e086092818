"""A body's person-to-person numbers — joint centres, segment masses and centres of mass,
landmarks, soles and each group's strength — in one fixed order, and a body whose numbers
are CasADi symbols, so that what is built on it (the task hierarchy, the torque model, the
solvers) serves every person of the same structure: scaling to another stature, mass, age
or strength changes numbers, not structure (docs/population.md).

Each point is given relative to the centre of the DOF that carries it (each DOF's centre
relative to its parent's), the offsets forward kinematics multiplies by, and a number that
is zero on the body a shape is built from (a point straight above its joint, on the
midline) stays an exact zero: a shape serves the bodies whose zeros lie at the same places
(``Shape.fits``). So the compiled functions have as many instructions as on the body's
numbers (32 581 instead of 32 159 for the 29-DOF standing wall hold's levels and Jacobians;
with world coordinates as symbols, 36 515: 20 % slower evaluations).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from casadi_posture.biomech.strength import ConstantStrength, ScaledCurveStrength, Strength
from casadi_posture.body.tree import BodyModel


def numbers(body: BodyModel, strength: Mapping[str, Strength]) -> np.ndarray:
    """The body's numbers in a fixed order, each point relative to the centre of the DOF
    that carries it: DOF origins (from the parent's), segment masses and centres of mass,
    landmarks, sole points [m, kg], then each half-joint's constant strength or shipped
    curve's value [N·m] (0 for a curve of a file's own, which is not a number of the body).
    Relative, so that a body rebuilt on symbols (``Shape``) has the offsets its forward
    kinematics uses as the symbols themselves, not differences computed at every call."""
    origin = {None: np.zeros(3)} | {d.name: np.asarray(d.origin, dtype=float) for d in body.dofs}
    out: list[float] = []
    for dof in body.dofs:
        out += (origin[dof.name] - origin[dof.parent]).tolist()
    for segment in body.segments:
        out += [segment.mass, *(np.asarray(segment.com) - origin[segment.dof])]
    for landmark in body.landmarks.values():
        out += (np.asarray(landmark.position) - origin[landmark.dof]).tolist()
    for foot in body.feet:
        out += [c for point in foot.outline for c in np.asarray(point) - origin[foot.dof]]
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
    origin: dict[str | None, tuple] = {None: (0.0, 0.0, 0.0)}

    def at(dof: str | None) -> tuple:
        base = origin[dof]
        return tuple(b + next(it) for b in base)

    dofs = []
    for d in body.dofs:
        origin[d.name] = at(d.parent)
        dofs.append(replace(d, origin=origin[d.name]))
    segments = []
    for s in body.segments:
        mass = next(it)
        segments.append(replace(s, mass=mass, com=at(s.dof)))
    landmarks = [replace(lm, position=at(lm.dof)) for lm in body.landmarks.values()]
    feet = [replace(f, outline=tuple(at(f.dof) for _ in f.outline)) for f in body.feet]
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
