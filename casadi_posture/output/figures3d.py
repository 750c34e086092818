"""The key postures of a run of a 3-D body: three orthographic views at one scale and a 3-D
view, the postures overlaid."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
from matplotlib.artist import Artist
from matplotlib.figure import Figure

from casadi_posture.output.key_postures import key_postures, title
from casadi_posture.output.saving import save_figure
from casadi_posture.output.scene import BODY, VIEWS, Pose, Scene, add_3d_view
from casadi_posture.simulation import SimulationResult

#: Largest height and width [in] of the views together; height [in] of a legend line, and
#: its most characters.
HEIGHT_IN, WIDTH_IN, ENTRY_IN, LEGEND_WIDTH = 7.0, 12.0, 0.17, 44

#: How much larger than its default the 3-D view draws its box (the 2-D views ignore it).
ZOOM_3D = 1.25


def _posture_label(scene: Scene, step: int, label: str) -> str:
    """A posture's legend entry, with its balance margin when the body stands."""
    margin = scene.margin(step)
    if margin is None:
        return label
    where = "inside" if margin >= 0 else "OUTSIDE"
    return f"{label}: COM {100 * abs(margin):.1f} cm {where} the support"


def _distinct_polygons(scene: Scene, steps: list[int]) -> set[int]:
    """The steps whose support polygon differs (by 1 mm) from every earlier one's."""
    fresh: set[int] = set()
    seen: list[np.ndarray] = []
    for step in steps:
        polygon = scene.polygons[step]
        if polygon is None or any(
            p.shape == polygon.shape and np.allclose(p, polygon, atol=1e-3) for p in seen
        ):
            continue
        seen.append(polygon)
        fresh.add(step)
    return fresh


def _handles(scene: Scene, shown: list[tuple[int, str, object]]) -> list[Artist]:
    """Legend entries: every posture, then the scene's."""
    postures = [
        scene.swatch(colour, _posture_label(scene, s, t), solid=k == 0, lw=2.6 if k == 0 else 1.6)
        for k, (s, t, colour) in enumerate(shown)
    ]
    return postures + scene.legend()


def postures_3d_figure(result: SimulationResult) -> Figure:
    """The initial, recovery and final postures overlaid in a sagittal, a frontal and a top
    view (one scale, metres) and a 3-D view: the bodies (the initial one opaque, the others
    translucent in outlines of their colour), each posture's centre of mass and its
    projection on the floor, the support polygon, the tasks' targets and the loads. The
    views are the axes labelled sagittal, frontal, top and 3-D."""
    shown = key_postures(result)
    scene = Scene.of_run(result, [step for step, _, _ in shown])
    dx, dy, dz = scene.spans
    wide = max(dx + dy, dz)  # the 3-D view's column [m]: its axes are square
    scale = min(HEIGHT_IN / (dz + dy), WIDTH_IN / (dx + dy + wide))  # in per m in every view
    handles = _handles(scene, shown)
    for handle in handles:
        handle.set_label(textwrap.fill(handle.get_label(), LEGEND_WIDTH, subsequent_indent="  "))
    rows = sum(handle.get_label().count("\n") + 1 for handle in handles)
    low = max(dy, (rows + 1) * ENTRY_IN / scale)  # the bottom row, legend beside [m]
    size = (scale * (dx + dy + wide) + 1.2, scale * (dz + low) + 1.0)
    fig = Figure(figsize=size, dpi=120)
    grid = fig.add_gridspec(2, 3, width_ratios=[dx, dy, wide], height_ratios=[dz, low])
    fig.subplots_adjust(left=0.07, right=0.99, bottom=0.06, top=0.92, wspace=0.35, hspace=0.3)
    cells = {"sagittal": grid[0, 0], "frontal": grid[0, 1], "top": grid[1, 0]}
    panels = [(fig.add_subplot(cells[name], label=name), *VIEWS[name]) for name in VIEWS]
    panels.append((add_3d_view(fig, grid[:, 2]), (0, 1, 2), ""))
    fresh = _distinct_polygons(scene, [step for step, _, _ in shown])
    for ax, axes, name in panels:
        scene.frame(ax, axes, zoom=ZOOM_3D)
        scene.draw_shapes(ax, axes)
        for k, (step, _, colour) in enumerate(shown):
            width = 2.6 if k == 0 else 1.6
            pose = Pose(
                ax, scene, axes, support=step in fresh, solid=k == 0, layer=BODY + 0.05 * k,
                color=colour, lw=width,
            )  # fmt: skip
            pose.update(step)
        ax.set_title(name, fontsize=9)
    legend = fig.add_subplot(grid[1, 1])
    legend.axis("off")
    legend.legend(handles=handles, loc="upper left", fontsize=7, frameon=False, borderaxespad=0)
    fig.suptitle(title(result), fontsize=10)
    return fig


def plot_postures_3d(result: SimulationResult, path: Path) -> Path:
    """``postures_3d_figure`` into ``path``."""
    return save_figure(postures_3d_figure(result), path, tight=False)
