"""The body over a run: its points [m] at every step, the bones that join them (the stick
figure), the mannequin's solids (a human body's) and the whole-body centre of mass [m]."""

from __future__ import annotations

import casadi as ca
import numpy as np
from matplotlib.axes import Axes

from casadi_posture.body.tree import BodyModel
from casadi_posture.output.mannequin import parts

#: World axes and their labels.
AXES = {0: "x forward (m)", 1: "y left (m)", 2: "z up (m)"}

#: A point of the figure: ("landmark", name) or ("centre", DOF name).
Key = tuple[str, str]


def _bones(body: BodyModel) -> list[tuple[Key, Key]]:
    """Each segment that names its end landmarks from one to the other; every body frame
    (the world's included) that carries no such segment by its tree: its joint centre
    joined to the joint centres of its children and to the landmarks it carries. The
    world's pieces (the root joint centres, the fixed landmarks) meet at the first root's
    centre. Bones of zero length at the zero posture, and repeats, are left out."""
    named = [s for s in body.segments if s.proximal and s.distal and s.proximal != s.distal]
    bones: list[tuple[Key, Key]] = [
        (("landmark", s.proximal), ("landmark", s.distal)) for s in named
    ]
    covered = {s.dof for s in body.segments if s.proximal and s.distal}
    roots = [d.name for d in body.dofs if d.parent is None]
    carried: dict[str | None, list[Key]] = {None: [("centre", r) for r in roots[1:]]}
    for dof in body.dofs:
        carried.setdefault(dof.name, [])
        if dof.parent is not None:
            carried[dof.parent].append(("centre", dof.name))
    for landmark in body.landmarks.values():
        carried[landmark.dof].append(("landmark", landmark.name))
    at_zero = {("centre", d.name): np.asarray(d.origin, dtype=float) for d in body.dofs}
    at_zero |= {("landmark", n): np.asarray(lm.position) for n, lm in body.landmarks.items()}
    seen = {tuple(np.round(np.concatenate([at_zero[a], at_zero[b]]), 9)) for a, b in bones}
    for frame, members in carried.items():
        if frame in covered or not roots:
            continue
        hub: Key = ("centre", frame if frame is not None else roots[0])
        for member in members:
            ends = tuple(np.round(np.concatenate([at_zero[hub], at_zero[member]]), 9))
            if np.allclose(at_zero[hub], at_zero[member], atol=1e-9) or ends in seen:
                continue
            seen.add(ends)
            bones.append((hub, member))
    return bones


class Skeleton:
    """The stick figure of ``body`` at every row of ``q`` (steps × DOFs [rad]): ``points``
    (steps × 3 × points [m]), ``bones`` (pairs of point indices), ``com`` (steps × 3 [m]:
    of the body and the ``carried`` point masses (landmark, kg), as the balance counts it),
    and the positions of the landmarks in ``extra`` (loads, effectors) as points too; the
    mannequin's ``parts`` (none for a body that is not human) and the placement of their
    frames at every step (``solids``). With ``steps``, only those rows of ``q`` are placed
    (the others are NaN): a figure of a few postures of a long run."""

    def __init__(
        self,
        body: BodyModel,
        q: np.ndarray,
        extra: tuple[str, ...] = (),
        carried: tuple[tuple[str, float], ...] = (),
        steps: list[int] | None = None,
    ) -> None:
        bones = _bones(body)
        keys = list(dict.fromkeys([k for bone in bones for k in bone]))
        keys += [k for k in (("landmark", n) for n in extra) if k not in keys]
        self.keys = keys
        self.bones = [(keys.index(a), keys.index(b)) for a, b in bones]
        self.joints = sorted({i for bone in self.bones for i in bone})
        expressions = [
            body.landmark(name)
            if kind == "landmark"
            else body.point(name, body.dofs[body.index[name]].origin)
            for kind, name in keys
        ]
        self.parts = parts(body)
        frames = list(dict.fromkeys(part.dof for part in self.parts))
        placements = [ca.horzcat(body.point(f, (0.0, 0.0, 0.0)), body.rotation(f)) for f in frames]
        outputs = [
            ca.horzcat(*expressions),
            body.com(carried),
            ca.horzcat(ca.SX(3, 0), *placements),
        ]
        q = np.atleast_2d(q) if len(q) else np.zeros((1, body.n))
        rows = np.arange(len(q)) if steps is None else np.unique(np.asarray(steps, dtype=int))
        function = ca.Function("skeleton", [body.q], outputs)
        points, com, placed = function.map(len(rows))(q[rows].T)  # 3 × (points·rows), ...
        self.points = np.full((len(q), 3, len(keys)), np.nan)
        self.points[rows] = np.asarray(points).reshape(3, -1, len(keys)).transpose(1, 0, 2)
        self.com = np.full((len(q), 3), np.nan)
        self.com[rows] = np.asarray(com).T
        #: steps × frames × 3 × 4: each frame's translation [m] and rotation (world = t + R x0)
        self._placed = np.full((len(q), len(frames), 3, 4), np.nan)
        shape = (3, len(rows), len(frames), 4)
        self._placed[rows] = np.asarray(placed).reshape(shape).transpose(1, 2, 0, 3)
        self._frame = [frames.index(part.dof) for part in self.parts]
        self._zero = [part.points() for part in self.parts]
        self.planar = body.planar
        spread = np.ptp(self.points[rows].transpose(1, 0, 2).reshape(3, -1), axis=1)
        self.plane = tuple(sorted(int(i) for i in np.argsort(spread)[-2:]))
        self.depth = next(i for i in range(3) if i not in self.plane)

    def solids(self, step: int) -> list[np.ndarray]:
        """The mannequin's parts at ``step``: each one's ring points (k × n × 3 [m])."""
        placed = self._placed[step]
        return [
            placed[f, :, 0] + zero @ placed[f, :, 1:].T
            for f, zero in zip(self._frame, self._zero, strict=True)
        ]

    def solids_extent(self, steps: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """The mannequin's parts at all of ``steps`` summed up without placing each point:
        the least and the greatest world coordinates [m] of their points, the points' sum
        [m] and how many there are (inf, -inf, 0, 0 for a body without parts)."""
        placed = self._placed[steps]
        lo, hi, total, count = np.full(3, np.inf), np.full(3, -np.inf), np.zeros(3), 0
        for f, zero in zip(self._frame, self._zero, strict=True):
            points = zero.reshape(-1, 3)
            origin, rotation = placed[:, f, :, 0], placed[:, f, :, 1:]
            turned = rotation @ points.T  # steps × 3 × points
            lo = np.minimum(lo, (origin + turned.min(axis=2)).min(axis=0))
            hi = np.maximum(hi, (origin + turned.max(axis=2)).max(axis=0))
            total += len(points) * origin.sum(axis=0) + rotation.sum(axis=0) @ points.sum(axis=0)
            count += len(points) * len(steps)
        return lo, hi, total, count

    def landmark(self, name: str, step: int) -> np.ndarray:
        """World position [m] of a landmark among the points at ``step``."""
        return self.points[step][:, self.keys.index(("landmark", name))]

    def segments(self, step: int) -> np.ndarray:
        """The bones at ``step`` as one polyline, bones apart by NaN rows (3k × 3 [m])."""
        xyz = self.points[step].T
        gap = np.full(3, np.nan)
        return np.array([row for a, b in self.bones for row in (xyz[a], xyz[b], gap)])

    def draw(self, ax: Axes, step: int, **style: object) -> None:
        """The stick figure at ``step`` in the plane of motion."""
        i, j = self.plane
        xyz = self.points[step]
        for a, b in self.bones:
            ax.plot([xyz[i, a], xyz[i, b]], [xyz[j, a], xyz[j, b]], "-", **style)
        ax.plot(xyz[i, self.joints], xyz[j, self.joints], "o", ms=4, color=style.get("color"))

    def frame(self, ax: Axes) -> None:
        """Equal axes in the plane of motion, labelled in metres."""
        ax.set_aspect("equal")
        ax.set_xlabel(AXES[self.plane[0]])
        ax.set_ylabel(AXES[self.plane[1]])
        ax.grid(alpha=0.3)

    def fit(self, ax: Axes) -> None:
        """Axis limits around every posture of the run, with a margin."""
        i, j = self.plane
        xs, ys = self.points[:, i].ravel(), self.points[:, j].ravel()
        margin = 0.08 * max(np.ptp(xs), np.ptp(ys), 0.1)
        ax.set_xlim(xs.min() - margin, xs.max() + margin)
        ax.set_ylim(ys.min() - margin, ys.max() + margin)
