"""The simulated hold as an animation: the body (a mannequin, or a stick figure for a body
that is not human) over time, coloured by the state of the fatigue-reducing constraint,
with the time [min] and a strip of the fatigue levels.

GIF through matplotlib's PillowWriter (Pillow comes with matplotlib: it always works); MP4
through FFMpegWriter when an ffmpeg program is on the PATH. The file is written under a
temporary name beside the target and renamed when complete."""

from __future__ import annotations

import os
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import animation
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.backend_bases import RendererBase
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from casadi_posture import interrupt
from casadi_posture.output.key_postures import title
from casadi_posture.output.movie_formats import WRITERS, check_format
from casadi_posture.output.scene import VIEWS, Pose, Scene, add_3d_view
from casadi_posture.output.time_axis import in_unit, time_unit
from casadi_posture.simulation import SimulationResult

#: Frames per second, and the most frames drawn (a longer run is subsampled evenly):
#: at most 12 s of animation whatever the run's length.
FPS, MAX_FRAMES = 10, 120

#: How much larger than its default the 3-D view draws its box; the most characters of a
#: legend line.
ZOOM_3D, LEGEND_WIDTH = 1.12, 26

#: The body's colour while no group owns the constraint, and while one does.
FREE, CONSTRAINED = "black", "tab:orange"
_COLOURS = ((FREE, "off"), (CONSTRAINED, "on"))


def frame_steps(steps: int, most: int = MAX_FRAMES) -> list[int]:
    """The steps drawn: every one of a short run, else ``most`` spread evenly, the first
    and the last included."""
    return sorted({int(k) for k in np.linspace(0, steps - 1, min(steps, most)).round()})


def _busiest_view(scene: Scene, steps: list[int]) -> str:
    """The side view (sagittal or frontal: a person is known by them) that shows the most
    motion of the body's points."""
    points = scene.skeleton.points[steps]
    motion = ((points - points[0]) ** 2).sum(axis=(0, 2))
    sides = [name for name, (axes, _) in VIEWS.items() if 2 in axes]
    return max(sides, key=lambda name: motion[list(VIEWS[name][0])].sum())


#: The animation's title on one line (9 inches at 10 points).
ANIMATION_TITLE_WIDTH = 130
#: Top of the fatigue strip's axis: room above fatigue 1 for its legend.
STRIP_TOP = 1.5


def _fatigue_strip(ax: Axes, result: SimulationResult) -> Line2D:
    """Fatigue [0–1] over time [min] of the groups that owned the constraint (or of the
    most tired one), both thresholds, the constraint shaded; returns the time cursor."""
    tl, s = result.timeline, result.settings
    times, unit = in_unit(tl.time)
    owners = list(dict.fromkeys(int(k) for k in tl.owner if k >= 0))
    groups = owners or [int(np.argmax(tl.fatigue.max(axis=0)))]
    halves = result.problem.body.half_joints
    for k in groups[:4]:
        ax.plot(times, tl.fatigue[:, k], lw=1.4, label=halves[k].name)
    ax.axhline(s.fatigue_threshold, color="tab:red", ls="--", lw=0.8)
    ax.axhline(s.recovery_threshold, color="tab:green", ls="--", lw=0.8)
    on = tl.owner >= 0
    if on.any():
        ax.fill_between(
            times,
            0,
            STRIP_TOP,
            where=on,
            color="0.88",
            step="post",
            zorder=0,
            label="constraint on",
        )
    ax.set_xlim(times[0], max(times[-1], times[0] + 1e-3))
    ax.set_ylim(0, STRIP_TOP)  # the legend sits above the curves (fatigue ≤ 1)
    ax.set_yticks([0.0, 0.5, 1.0])
    ax.set_xlabel(f"time ({unit})", fontsize=8)
    ax.set_ylabel("fatigue", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7, loc="upper left", ncol=min(len(groups) + 1, 5), frameon=False)
    return ax.axvline(times[0], color="black", lw=1.2)


def _state(result: SimulationResult, step: int) -> str:
    """The time (min and s, or s for a run of 5 min or less) and the constraint's state at
    ``step`` in words."""
    tl = result.timeline
    _, unit = time_unit(tl.time)
    when = (
        f"{tl.time[step] / 60:.1f} min ({tl.time[step]:g} s)"
        if unit == "min"
        else f"{tl.time[step]:g} s"
    )
    text = f"t = {when}   constraint: "
    owner = int(tl.owner[step])
    if owner < 0:
        return text + "off"
    half = result.problem.body.half_joints[owner]
    goal = (
        f", goal {half.dof} {np.degrees(tl.goal[step]):.1f}°" if np.isfinite(tl.goal[step]) else ""
    )
    return text + f"on, owned by {half.name}{goal}"


class MovingFigure(Figure):
    """A figure whose every draw after the first paints only its ``moving`` artists over
    the first draw's pixels of the rest, which stays as it was: a frame of the 29-DOF
    standing wall's animation then takes 0.2 s instead of 0.4 (its legends, titles and
    fatigue strip are two thirds of a full draw). The writers grab each frame by saving
    the figure, which draws it."""

    moving: tuple[Artist, ...] = ()
    _still: Any = None

    def draw(self, renderer: RendererBase) -> None:
        if self._still is None:
            for artist in self.moving:
                artist.set_animated(True)  # left out of the full draw
            super().draw(renderer)
            self._still = renderer.copy_from_bbox(self.bbox)
        else:
            renderer.restore_region(self._still)
        for artist in self.moving:
            artist.draw(renderer)


class _Frames:
    """The animation's figure: for a 3-D body a 3-D view and the side view that shows the
    most motion, for a planar body its plane of motion, a legend beside; the state of the
    constraint above, a strip of fatigue below; ``draw`` shows a step."""

    def __init__(self, result: SimulationResult, steps: list[int]) -> None:
        self.result = result
        scene = Scene.of_run(result, steps)
        self.fig = fig = MovingFigure(figsize=(9.0, 6.0), dpi=100)
        grid = fig.add_gridspec(
            2, 3, height_ratios=[4.5, 1.1], width_ratios=[1.5, 0.9, 0.9], left=0.05, right=0.99,
            top=0.87, bottom=0.08, hspace=0.3, wspace=0.4,
        )  # fmt: skip
        if scene.skeleton.planar:
            name = next(n for n, (axes, _) in VIEWS.items() if axes == scene.skeleton.plane)
            views = [(fig.add_subplot(grid[0, :2]), *VIEWS[name])]
        else:
            views = [
                (add_3d_view(fig, grid[0, 0]), (0, 1, 2), ""),
                (fig.add_subplot(grid[0, 1]), *VIEWS[_busiest_view(scene, steps)]),
            ]
        self.poses = []
        for ax, axes, name in views:
            scene.frame(ax, axes, zoom=ZOOM_3D)
            scene.draw_shapes(ax, axes, labels=False)
            self.poses.append(Pose(ax, scene, axes, color=FREE, lw=2.2))
            ax.set_title(name, fontsize=9)
        self.cursor = _fatigue_strip(fig.add_subplot(grid[1, :]), result)
        key = fig.add_subplot(grid[0, 2])
        key.axis("off")
        states = [scene.swatch(c, f"constraint {w}", lw=2.2) for c, w in _COLOURS]
        handles = states + scene.legend(names=False)
        for handle in handles:
            handle.set_label(
                textwrap.fill(handle.get_label(), LEGEND_WIDTH, subsequent_indent="  ")
            )
        key.legend(handles=handles, loc="center left", fontsize=7, frameon=False, borderaxespad=0)
        fig.suptitle(title(result, width=ANIMATION_TITLE_WIDTH), fontsize=10, y=0.985)
        self.state = fig.text(0.5, 0.925, "", ha="center", fontsize=9)
        fig.moving = (*(pose.ax for pose in self.poses), self.cursor, self.state)

    def draw(self, step: int) -> None:
        """Show the posture, the time and the constraint's state at ``step``."""
        tl = self.result.timeline
        colour = CONSTRAINED if tl.owner[step] >= 0 else FREE
        for pose in self.poses:
            pose.recolour(colour)
            pose.update(step)
        self.cursor.set_xdata([tl.time[step] / time_unit(tl.time)[0]] * 2)
        self.state.set_text(_state(self.result, step))
        self.state.set_color(colour)


def write_animation(result: SimulationResult, path: Path) -> Path | None:
    """Animate the run into ``path`` (.gif or .mp4), at most ``MAX_FRAMES`` frames at
    ``FPS``. Returns None, leaving no file, for a run without steps or when Ctrl-C
    (or an earlier one in the same command) stops it between frames."""
    writer = animation.writers[WRITERS[check_format(path.suffix.lstrip(".").lower(), "path")]]
    if result.timeline.time.size == 0 or interrupt.requested():
        return None
    steps = frame_steps(result.timeline.time.size)
    frames = _Frames(result, steps)
    temporary = path.with_name(f".{path.stem}-partial{path.suffix}")
    path.parent.mkdir(parents=True, exist_ok=True)
    movie = writer(fps=FPS)
    movie.setup(frames.fig, str(temporary), dpi=frames.fig.dpi)
    try:
        for step in steps:
            frames.draw(step)
            movie.grab_frame()
            if interrupt.requested():
                break
        movie.finish()  # also after Ctrl-C, to free the writer: the file is then deleted
        if interrupt.requested():
            return None
        os.replace(temporary, path)
        return path
    finally:
        temporary.unlink(missing_ok=True)
