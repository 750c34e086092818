"""What the 3-D posture figures and the animation draw of a run, in orthographic views and a
3-D view: the mannequin (a stick figure for a body that is not human), the whole-body centre
of mass and its vertical projection on the floor, the support polygon, the tasks' targets
(points, lines, planes) and the loads."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.gridspec import SubplotSpec
from matplotlib.lines import Line2D
from matplotlib.patches import FancyArrowPatch, Patch, Polygon
from matplotlib.ticker import MaxNLocator
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from casadi_posture.body.support import margin, support_polygon
from casadi_posture.ik.tasks import CentreOfMass, Line, Plane, Task
from casadi_posture.output.mannequin import (
    CONTEXT,
    TASK_WHITE,
    Mannequin,
    limbs_of,
    swatch,
    tint,
)
from casadi_posture.output.skeleton import AXES, Skeleton
from casadi_posture.problem import Problem
from casadi_posture.simulation import SimulationResult

#: The orthographic views: world axes drawn across and up, and what the view looks at.
VIEWS = {
    "sagittal": ((0, 2), "sagittal view, from the right"),
    "frontal": ((1, 2), "frontal view, from the front"),
    "top": ((0, 1), "top view, from above"),
}

#: Colours of the scene around the body: solid, not translucent, so that a GIF's palette
#: stays small.
TARGET, SUPPORT, FLOOR = "0.35", "#b5dcb5", "0.92"
EDGE = "#3c8c3c"  # the support polygon's edge, seen from above

#: zorders: the postures (one layer each, the first at BODY), then what is drawn over them.
BODY, OVER = 2.0, 5.0

#: Points below this height [m] put the body partly under the floor: no floor is drawn
#: (a body whose origin is not on the floor, such as an arm at the shoulder).
FLOOR_TOLERANCE = 0.01


@dataclass(frozen=True)
class Shape:
    """A task's target set [m, world]: a point, a line through ``point`` along ``vector``,
    or a plane through ``point`` normal to ``vector`` (unit)."""

    name: str
    kind: Literal["point", "line", "plane"]
    point: np.ndarray
    vector: np.ndarray


def _unit(vector: object) -> np.ndarray:
    v = np.asarray(vector, dtype=float)
    return v / np.linalg.norm(v)


def task_shapes(tasks: tuple[Task, ...]) -> list[Shape]:
    """The target sets of the tasks that have one: a line, a plane, a centre-of-mass target
    (a point, a vertical line or a plane, by its free axes), any task's target point."""
    shapes = []
    for task in tasks:
        if isinstance(task, Line):
            shapes.append(Shape(task.name, "line", np.asarray(task.point), _unit(task.direction)))
        elif isinstance(task, Plane):
            shapes.append(Shape(task.name, "plane", np.asarray(task.point), _unit(task.normal)))
        elif isinstance(task, CentreOfMass):
            free = [i for i in range(3) if "xyz"[i] not in task.axes]
            name = f"{task.name} (centre of mass, {task.axes})"
            point = np.asarray(task.target, dtype=float)
            if len(free) == 1:
                shapes.append(Shape(name, "line", point, np.eye(3)[free[0]]))
            elif len(free) == 2:
                fixed = next(i for i in range(3) if i not in free)
                shapes.append(Shape(name, "plane", point, np.eye(3)[fixed]))
            elif not free:
                shapes.append(Shape(name, "point", point, np.zeros(3)))
        elif len(np.atleast_1d(getattr(task, "target", ()))) == 3:
            target = np.asarray(task.target, dtype=float)
            shapes.append(Shape(task.name, "point", target, np.zeros(3)))
    return shapes


def clip_line(point: np.ndarray, direction: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """The two ends [m] of a line's part inside the box ``lo``–``hi``, or None."""
    t0, t1 = -np.inf, np.inf
    for k in range(3):
        if abs(direction[k]) < 1e-12:
            if not lo[k] <= point[k] <= hi[k]:
                return None
            continue
        a, b = sorted(((lo[k] - point[k]) / direction[k], (hi[k] - point[k]) / direction[k]))
        t0, t1 = max(t0, a), min(t1, b)
    return None if t0 > t1 else point + np.outer([t0, t1], direction)


def plane_polygon(point: np.ndarray, normal: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """The polygon (k × 3) [m] where a plane cuts the box ``lo``–``hi``, or None."""
    corners = np.array([[(lo, hi)[(c >> k) & 1][k] for k in range(3)] for c in range(8)])
    side = (corners - point) @ normal
    cuts = []
    for a in range(8):
        for k in range(3):
            b = a | (1 << k)
            if b != a and side[a] * side[b] <= 0 and side[a] != side[b]:
                t = side[a] / (side[a] - side[b])
                cuts.append(corners[a] + t * (corners[b] - corners[a]))
    if len(cuts) < 3:
        return None
    cuts = np.unique(np.round(cuts, 12), axis=0)
    centre = cuts.mean(axis=0)
    u = _unit(np.cross(normal, np.eye(3)[int(np.argmin(np.abs(normal)))]))
    v = np.cross(normal, u)
    order = np.argsort(np.arctan2((cuts - centre) @ v, (cuts - centre) @ u))
    return cuts[order]


def add_3d_view(fig: Figure, cell: SubplotSpec) -> Axes:
    """A 3-D view in a grid cell, seen from the front right and a little above, titled
    above the cell (the zoomed box may reach over the axes' own title); drawn in the
    order of its artists' zorder, not by depth."""
    ax = fig.add_subplot(cell, projection="3d", label="3-D")
    ax.view_init(elev=15, azim=-55)
    ax.computed_zorder = False  # the floor, then the support polygon, then the lines
    box = cell.get_position(fig)
    fig.text((box.x0 + box.x1) / 2, box.y1, "3-D view", ha="center", va="bottom", fontsize=9)
    return ax


class Scene:
    """The skeleton of ``problem``'s body at the postures ``q`` (rows [rad]), its centre of
    mass, support polygons, the ``tasks``' shapes and the loads, the ``task_limbs`` (those
    that carry a task's effector or segment or a load), and a box [m] around them at the
    rows ``steps`` that will be drawn (a 3-D body is placed at those rows only)."""

    def __init__(
        self, problem: Problem, tasks: Sequence[Task], q: np.ndarray, steps: list[int]
    ) -> None:
        self.problem, self.q = problem, q
        down = np.array([0.0, 0.0, -problem.body.gravity])
        forces = [(load.at, load.mass * down + load.force, load) for load in problem.loads]
        self.loads = [(at, force, load) for at, force, load in forces if force.any()]
        extra = tuple(dict.fromkeys(at for at, _, _ in self.loads))
        carried = tuple((load.at, load.mass) for load in problem.loads if load.mass > 0)
        placed = None if problem.body.planar else steps  # a plane is found from all steps
        self.skeleton = Skeleton(problem.body, q, extra, carried, placed)
        self.shapes = task_shapes(tuple(tasks))
        effectors = [getattr(task, "effector", None) for task in tasks]
        effectors += [at for at, _, _ in self.loads]
        segments = [getattr(task, "segment", None) for task in tasks]
        self.task_limbs = limbs_of(
            problem.body, self.skeleton.parts, filter(None, effectors), filter(None, segments)
        )
        self.polygons = {s: support_polygon(problem.body, q[s]) for s in steps}
        points = np.concatenate([self.skeleton.points[s].T for s in steps])
        self.floor = bool(points[:, 2].min() > -FLOOR_TOLERANCE)
        self.arrow = 0.12 * float(np.ptp(points, axis=0).max())
        reach = [points, self.skeleton.com[steps]]
        reach += [np.c_[p, np.zeros(len(p))] for p in self.polygons.values() if p is not None]
        for at, force, _ in self.loads:
            reach += [self.skeleton.landmark(at, s) + self.arrow * _unit(force) for s in steps]
        lo, hi, total, count = self.skeleton.solids_extent(steps)
        body = np.vstack([*reach, *([lo, hi] if count else [])])
        centre = (np.vstack(reach).sum(axis=0) + total) / (sum(map(len, reach)) + count)
        span = np.ptp(body, axis=0)
        near = [
            s.point[None]
            for s in self.shapes
            if s.kind == "point" and np.all(np.abs(s.point - centre) < span + 0.5)
        ]
        floor = [np.array([[centre[0], centre[1], 0.0]])] if self.floor else []
        box = np.vstack([body, *near, *floor])
        pad = 0.08 * max(float(np.ptp(box, axis=0).max()), 0.1)
        self.lo, self.hi = box.min(axis=0) - pad, box.max(axis=0) + pad

    @classmethod
    def of_run(cls, result: SimulationResult, steps: list[int]) -> Scene:
        """The scene of a simulated run at its timeline's ``steps``."""
        return cls(result.problem, result.tasks, result.timeline.q, steps)

    @property
    def spans(self) -> np.ndarray:
        """The box's size along x, y, z [m]."""
        return self.hi - self.lo

    def margin(self, step: int) -> float | None:
        """Signed distance [m] of the centre of mass's projection to the support polygon's
        edge at ``step`` (positive inside), or None without a polygon."""
        polygon = self.polygons.get(step)
        if polygon is None or len(polygon) < 3:
            return None
        return margin(polygon, self.skeleton.com[step, :2])

    def swatch(self, colour: object, label: str, *, solid: bool = True, lw: float = 2.0) -> Artist:
        """A legend entry of a posture: its mannequin's fill and outline, or a line."""
        if self.skeleton.parts:
            return swatch(colour, solid, label)
        return Line2D([], [], color=colour, lw=lw, label=label)

    def legend(self, *, names: bool = True) -> list[Artist]:
        """Legend entries of what surrounds the postures: the task limbs' shade, the centre
        of mass, its projection, the support polygon, the task shapes (with the tasks'
        ``names``) and the loads."""
        handles: list[Artist] = []
        if self.task_limbs:
            limbs = ", ".join(sorted(self.task_limbs, reverse=True))
            label = f"deeper shade: task limb{'s' * (len(self.task_limbs) > 1)} ({limbs})"
            handles.append(Patch(fc=tint("black", TASK_WHITE), ec="black", label=label))
        context = {part.name for part in self.skeleton.parts if part.context}
        if context:
            drawn = "legs and stool" if "seat" in context else "legs"
            label = f"grey: {drawn}, not modelled (context)"
            handles.append(Patch(fc=CONTEXT[0], ec=CONTEXT[1], label=label))
        handles.append(
            Line2D([], [], ls="", marker="o", ms=8, mfc="white", mec="0.2", mew=1.8,
                   label="whole-body centre of mass (COM)")
        )  # fmt: skip
        if self.floor:
            handles.append(
                Line2D([], [], ls=":", marker="x", color="0.2", label="COM projected on the floor")
            )
        if any(p is not None for p in self.polygons.values()):
            handles.append(Patch(fc=SUPPORT, ec=EDGE, label="support polygon (feet)"))
        styles = {"point": {"ls": "", "marker": "x", "mew": 2}, "line": {"ls": "--"}}
        for kind in ("point", "line", "plane"):
            shown = [shape.name for shape in self.shapes if shape.kind == kind]
            if shown:
                label = "target" if kind == "point" else f"task {kind}"
                label += f": {', '.join(shown)}" if names else "s" * (len(shown) > 1)
                style = styles.get(kind, {"ls": ":"})
                handles.append(Line2D([], [], color=TARGET, label=label, **style))
        for _, force, load in self.loads:
            what = f"{load.mass:g} kg" if load.mass > 0 else f"{np.linalg.norm(force):.0f} N"
            handles.append(
                Line2D([], [], color="0.2", marker=r"$\downarrow$", ls="", ms=10,
                       label=f"load {load.name}: {what} at {load.at}")
            )  # fmt: skip
        return handles

    def frame(self, ax: Axes, axes: tuple[int, ...], *, zoom: float = 1.15) -> None:
        """Limits of the box, equal scales, labels in metres, and the floor; a 3-D box drawn
        ``zoom`` times its default size."""
        if len(axes) == 3:
            ax.set_xlim(self.lo[0], self.hi[0])
            ax.set_ylim(self.lo[1], self.hi[1])
            ax.set_zlim(self.lo[2], self.hi[2])
            ax.set_box_aspect(tuple(self.spans), zoom=zoom)
            for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
                axis.set_major_locator(MaxNLocator(5))
            ax.set_xlabel(AXES[0], fontsize=7, labelpad=-2)
            ax.set_ylabel(AXES[1], fontsize=7, labelpad=-2)
            ax.set_zlabel(AXES[2], fontsize=7, labelpad=-2)
            ax.tick_params(labelsize=6, pad=-2)
            if self.floor:
                x0, x1, y0, y1 = self.lo[0], self.hi[0], self.lo[1], self.hi[1]
                floor = [[(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0)]]
                ax.add_collection3d(Poly3DCollection(floor, color=FLOOR, zorder=0))
            return
        i, j = axes
        ax.set_xlim(self.lo[i], self.hi[i])
        ax.set_ylim(self.lo[j], self.hi[j])
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(AXES[i], fontsize=8)
        ax.set_ylabel(AXES[j], fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        if self.floor and j == 2:
            ax.axhspan(self.lo[2], 0.0, color=FLOOR, zorder=0)
            ax.axhline(0.0, color="0.5", lw=0.8, zorder=0)

    def draw_shapes(self, ax: Axes, axes: tuple[int, ...], *, labels: bool = True) -> None:
        """The task shapes clipped to the box: points as crosses, lines dashed, planes as
        translucent patches in 3-D and, seen edge-on, dotted in a view."""
        for shape in self.shapes:
            label = shape.name if labels else None
            style = {"color": TARGET, "label": label, "zorder": OVER}
            if shape.kind == "point":
                ax.plot(*shape.point[list(axes)], "x", ms=8, mew=2, **style)
                continue
            if shape.kind == "line":
                ends = clip_line(shape.point, shape.vector, self.lo, self.hi)
                if ends is None:
                    continue
                if len(axes) == 2 and np.linalg.norm(shape.vector[list(axes)]) < 1e-9:
                    ax.plot(*shape.point[list(axes)], "+", ms=10, mew=1.5, **style)
                else:
                    ax.plot(*ends[:, list(axes)].T, ls="--", lw=1.2, **style)
                continue
            corners = plane_polygon(shape.point, shape.vector, self.lo, self.hi)
            if corners is None:
                continue
            if len(axes) == 3:
                ax.add_collection3d(
                    Poly3DCollection([corners], color=TARGET, alpha=0.12, label=label)
                )
            elif abs(shape.vector[3 - sum(axes)]) < 1e-9:
                flat = corners[:, list(axes)]
                ends = flat[[np.argmin(flat @ flat[0]), np.argmax(flat @ flat[0])]]
                ax.plot(*ends.T, ls=":", lw=1.5, **style)


class Pose:
    """One posture of the run drawn in one view (2 world axes) or in 3-D (3): the mannequin
    (``solid`` or translucent, in zorder ``layer``) or the bones and joints of a body that
    is not human, centre of mass with its drop line to the floor, support polygon (unless
    not ``support``) and load arrows, all moved to another step by ``update``."""

    def __init__(
        self,
        ax: Axes,
        scene: Scene,
        axes: tuple[int, ...],
        *,
        support: bool = True,
        solid: bool = True,
        layer: float = BODY,
        **style: object,
    ) -> None:
        self.ax, self.scene, self.axes = ax, scene, list(axes)
        self.three = len(axes) == 3
        colour = style.pop("color", "black")
        lw = float(style.pop("lw", 2.0))
        self.mannequin = (
            Mannequin(ax, scene.skeleton, self.axes, task=scene.task_limbs, solid=solid,
                      layer=layer, colour=colour)
            if scene.skeleton.parts
            else None
        )  # fmt: skip
        (self.bones,) = ax.plot(*[[]] * len(axes), "-", color=colour, lw=lw, zorder=layer, **style)
        (self.joints,) = ax.plot(*[[]] * len(axes), "o", ms=2.5, color=colour, zorder=layer)
        com = {"ms": 8, "mfc": "white", "mec": colour, "mew": 1.8, "zorder": OVER + 0.2}
        (self.com,) = ax.plot(*[[]] * len(axes), "o", **com)
        (self.drop,) = ax.plot(*[[]] * len(axes), ":", color=colour, lw=1.0, zorder=OVER)
        (self.ground,) = ax.plot(*[[]] * len(axes), "x", color=colour, ms=5, mew=1.2, zorder=OVER)
        self.support = self._support_artist()
        # From above, the body hides the polygon: its edge is drawn over the body.
        (self.edge,) = ax.plot(*[[]] * len(axes), "-", color=EDGE, lw=1.2, zorder=OVER)
        self.show_support = support
        for artist, gid in (
            (self.bones, "bones"),
            (self.com, "com"),
            (self.drop, "com-drop"),
            (self.ground, "com-floor"),
            (self.support, "support"),
            (self.edge, "support-edge"),
        ):
            artist.set_gid(gid)
        self.arrows: list = []
        self.colour = colour

    def _support_artist(self):
        style = {"color": SUPPORT, "zorder": BODY - 0.5}
        if self.three:
            return self.ax.add_collection3d(Poly3DCollection([], **style))
        if self.axes == [0, 1]:
            return self.ax.add_patch(Polygon(np.zeros((3, 2)), closed=True, visible=False, **style))
        (line,) = self.ax.plot([], [], "-", lw=5, solid_capstyle="butt", **style)
        return line

    def _set(self, line, xyz: np.ndarray) -> None:
        """Points (k × 3) [m] into a line, projected on the view's axes."""
        data = [xyz[:, k] for k in self.axes]
        if self.three:
            line.set_data_3d(*data)
        else:
            line.set_data(*data)

    def recolour(self, colour: object) -> None:
        """Draw the posture in another colour (the constraint's state in the animation)."""
        for line in (self.bones, self.joints, self.drop, self.ground):
            line.set_color(colour)
        self.com.set_markeredgecolor(colour)
        if self.mannequin is not None:
            self.mannequin.recolour(colour)
        self.colour = colour

    def update(self, step: int) -> None:
        """Move every part to the posture at ``step``."""
        scene, skeleton = self.scene, self.scene.skeleton
        if self.mannequin is not None:
            self.mannequin.update(step)
        else:
            self._set(self.bones, skeleton.segments(step))
            self._set(self.joints, skeleton.points[step][:, skeleton.joints].T)
        com = skeleton.com[step]
        self._set(self.com, com[None])
        floor = np.array([com[0], com[1], 0.0])
        self._set(self.drop, np.array([com, floor]) if scene.floor else np.zeros((0, 3)))
        self._set(self.ground, floor[None] if scene.floor else np.zeros((0, 3)))
        self._draw_support(scene.polygons[step] if self.show_support else None)
        self._draw_loads(step)

    def _draw_support(self, polygon: np.ndarray | None) -> None:
        shown = polygon is not None and len(polygon) >= 3
        self.support.set_visible(shown)
        self.edge.set_visible(shown and self.axes == [0, 1])
        if not shown:
            return
        if self.three:
            self.support.set_verts([np.c_[polygon, np.zeros(len(polygon))]])
        elif self.axes == [0, 1]:
            self.support.set_xy(polygon)
            self.edge.set_data(*np.vstack([polygon, polygon[:1]]).T)
        else:
            k = self.axes[0]
            self.support.set_data([polygon[:, k].min(), polygon[:, k].max()], [0.0, 0.0])

    def _draw_loads(self, step: int) -> None:
        for arrow in self.arrows:
            arrow.remove()
        self.arrows = []
        scene = self.scene
        for at, force, _ in scene.loads:
            start = scene.skeleton.landmark(at, step)
            end = start + scene.arrow * _unit(force)
            if self.three:
                vector = end - start
                self.arrows.append(
                    self.ax.quiver(
                        *start,
                        *vector,
                        color=self.colour,
                        lw=1.2,
                        arrow_length_ratio=0.3,
                        zorder=OVER,
                    )
                )
            elif np.linalg.norm((end - start)[self.axes]) > 1e-9:
                arrow = FancyArrowPatch(
                    tuple(start[self.axes]),
                    tuple(end[self.axes]),
                    arrowstyle="-|>",
                    mutation_scale=10,
                    color=self.colour,
                    lw=1.2,
                    zorder=OVER,
                )
                self.arrows.append(self.ax.add_patch(arrow))
