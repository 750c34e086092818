"""Standing on the floor: the support polygon of the feet and the floor's reaction on the
second foot (docs/model.md, "Standing").

A standing body's tree is rooted at one foot, fixed to the world; the other foot is carried
by the leg's DOFs and kept on the floor by a task. With both feet down the floor's
reaction is statically indeterminate; the model splits it by a stated rule:

- the resultant of every applied force (gravity on the segments, held loads, pushes) and
  moment has a centre of pressure ``c`` on the floor, where its moment about the vertical
  axis through ``c`` has no horizontal part;
- the vertical load ``W`` is shared by the lever rule along the line joining the centres of
  the two soles: the carried foot takes ``s·W``, with ``s`` the position of ``c`` projected
  on that line (0 at the root foot, 1 at the carried one);
- both feet press at the same offset ``d`` from that line, so the two pressures add up to
  ``W`` at ``c``;
- the horizontal force and the moment about the vertical through ``c`` are shared by the
  same rule: the carried foot takes the share ``s`` of the whole reaction (force and that
  moment), at the centre of its sole plus ``d`` on the floor; the root foot, whose reaction
  needs no torque of the DOFs, takes the rest. The two reactions add up to the applied
  resultant at ``c`` for any ``s``: a symmetric stance shares a symmetric push equally.

The carried foot's reaction enters the external torque by virtual work like a push. An
``s`` outside [0, 1] (the centre of pressure beyond a foot) needs the floor to pull that
foot down: ``floor_pressure`` gives ``s`` and ``c`` so that answers can flag them.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel, Foot


def sole_points(body: BodyModel, foot: Foot) -> ca.SX:
    """3×k world positions [m] of a foot's outline at the posture ``body.q``."""
    return ca.horzcat(*[body.point(foot.dof, p) for p in foot.outline])


def _sole_centre(body: BodyModel, foot: Foot) -> ca.SX:
    """World position of a foot's sole centre (the mean of its outline)."""
    return body.point(foot.dof, ca.vertsplit(foot.centre()))


def carried_foot(body: BodyModel) -> Foot | None:
    """The foot the tree's DOFs carry, if the body stands on two feet."""
    if len(body.feet) != 2:
        return None
    return next(f for f in body.feet if f.dof is not None)


def _resultant(
    forces: Sequence[tuple[ca.SX, ca.SX]], moments: Sequence[ca.SX]
) -> tuple[ca.SX, ca.SX]:
    """The applied force [N] and its moment about the world origin [N·m]."""
    total = sum((f for _, f in forces), ca.SX.zeros(3))
    moment = sum((ca.cross(x, f) for x, f in forces), ca.SX.zeros(3))
    return total, moment + sum(moments, ca.SX.zeros(3))


def _pressure_and_share(
    body: BodyModel, foot: Foot, total: ca.SX, moment: ca.SX
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """The centre of pressure ``c`` (x, y) [m], the carried foot's share ``s`` [-] and its
    sole centre [m] for an applied resultant (force [N], moment about the origin [N·m])."""
    root = next(f for f in body.feet if f.dof is None)
    pressure = ca.vertcat(-moment[1] / total[2], moment[0] / total[2])
    root_centre = root.centre()[:2]
    centre = _sole_centre(body, foot)
    line = centre[:2] - root_centre
    share = ca.dot(pressure - root_centre, line) / ca.dot(line, line)
    return pressure, share, centre


def reaction_torque(
    body: BodyModel, forces: Sequence[tuple[ca.SX, ca.SX]], moments: Sequence[ca.SX]
) -> ca.SX:
    """Torque [N·m] on every DOF of the floor's reaction on the carried foot, for applied
    ``forces`` (point [m], force [N], world) and pure ``moments`` [N·m]; zero for a body not
    standing on two feet."""
    foot = carried_foot(body)
    if foot is None:
        return ca.SX.zeros(body.n)
    total, moment = _resultant(forces, moments)
    pressure, share, centre = _pressure_and_share(body, foot, total, moment)
    root_centre = next(f for f in body.feet if f.dof is None).centre()[:2]
    offset = pressure - (root_centre + share * (centre[:2] - root_centre))
    # Moment of the applied resultant about the vertical through c (its only part there).
    twist = moment[2] - (pressure[0] * total[1] - pressure[1] * total[0])
    force = -share * total
    arm = ca.vertcat(offset, -centre[2])
    couple = ca.vertcat(0.0, 0.0, -share * twist)
    # On each DOF up the foot's chain: a_j · ((centre − o_j) × force + arm × force + couple),
    # written out rather than through the Jacobians of the centre and the foot's frame,
    # which the comfort level would differentiate again (three times the instructions).
    about = ca.cross(arm, force) + couple
    chain = set(body.ancestors(foot.dof))
    return ca.vertcat(
        *[
            ca.dot(
                body.joint_axis(d.name),
                ca.cross(centre - body.joint_centre(d.name), force) + about,
            )
            if d.name in chain
            else ca.SX(0.0)
            for d in body.dofs
        ]
    )


def floor_pressure(
    body: BodyModel, forces: Sequence[tuple[ca.SX, ca.SX]], moments: Sequence[ca.SX]
) -> tuple[ca.SX, ca.SX]:
    """The centre of pressure ``c`` (x, y) [m] of the applied ``forces`` and ``moments`` and
    the carried foot's share ``s`` [-] of the floor's reaction (0: all on the root foot, 1:
    all on the carried one; outside [0, 1] the rule has the floor pull a foot down), for a
    body standing on two feet."""
    foot = carried_foot(body)
    if foot is None:
        raise ValueError("the floor's reaction is shared only by a body standing on two feet")
    pressure, share, _ = _pressure_and_share(body, foot, *_resultant(forces, moments))
    return pressure, share


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D ``points`` (k×2) counter-clockwise, by Andrew's monotone chain."""
    pts = sorted({(float(x), float(y)) for x, y in points})
    if len(pts) < 3:
        return np.asarray(pts)

    def half(sequence: list[tuple[float, float]]) -> list[tuple[float, float]]:
        chain: list[tuple[float, float]] = []
        for p in sequence:
            while len(chain) >= 2:
                (ax, ay), (bx, by) = chain[-2], chain[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 0:
                    break
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(pts[::-1])
    return np.asarray(lower[:-1] + upper[:-1])


def margin(polygon: np.ndarray, point: np.ndarray) -> float:
    """Signed distance [m] of a floor ``point`` (x, y) to the edge of a counter-clockwise
    convex ``polygon``: positive inside, negative outside."""
    a = np.asarray(polygon, dtype=float)
    edge = np.roll(a, -1, axis=0) - a
    square = np.einsum("ij,ij->i", edge, edge)
    to_point = np.asarray(point, dtype=float) - a
    along = np.clip(np.einsum("ij,ij->i", to_point, edge) / square, 0.0, 1.0)
    distance = np.hypot(*(to_point - along[:, None] * edge).T)
    beyond = to_point[:, 1] * edge[:, 0] - to_point[:, 0] * edge[:, 1] < 0  # right of the edge
    outside = float(distance[beyond].max()) if beyond.any() else 0.0
    return -outside if outside > 0 else float(distance.min())


class Support:
    """The support polygon of a body's feet, compiled once per body."""

    def __init__(self, body: BodyModel) -> None:
        self.body = body
        points = [sole_points(body, foot) for foot in body.feet]
        self._points = ca.Function("soles", [body.q], [ca.horzcat(*points)]) if points else None

    def balance(
        self, postures: np.ndarray, carried: Sequence[tuple[str, float]] = ()
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """For each posture (rows, rad): the floor projection (x, y) [m] of the centre of
        mass of the body and the ``carried`` point masses (landmark, kg), and its margin
        [m] inside the support polygon (negative: outside); ``None`` without feet."""
        if self._points is None:
            return None
        body = self.body
        com = body.com(carried)
        f = ca.Function("balance", [body.q], [com[:2], self._points(body.q)])
        # each distinct posture once: a hold that does not move repeats one row
        distinct, back = np.unique(np.asarray(postures, dtype=float), axis=0, return_inverse=True)
        many = f.map(len(distinct))
        ground, soles = (np.asarray(v) for v in many(distinct.T))
        k = soles.shape[1] // len(distinct)
        margins = np.array(
            [
                margin(convex_hull(soles[:2, i * k : (i + 1) * k].T), ground[:, i])
                for i in range(len(distinct))
            ]
        )
        back = np.ravel(back)
        return ground.T[back], margins[back]

    def polygon(self, q: np.ndarray) -> np.ndarray | None:
        """Convex hull (k×2, counter-clockwise) [m] of the soles on the floor at posture
        ``q`` [rad]; ``None`` for a body without feet."""
        if self._points is None:
            return None
        points = np.asarray(self._points(q))
        return convex_hull(points[:2].T)


@lru_cache(maxsize=8)
def _support(body: BodyModel) -> Support:
    return Support(body)


def support_polygon(body: BodyModel, q: np.ndarray) -> np.ndarray | None:
    """The support polygon of ``body`` at posture ``q`` [rad] (see ``Support``)."""
    return _support(body).polygon(np.asarray(q, dtype=float))
