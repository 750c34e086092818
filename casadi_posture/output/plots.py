"""Figures, drawn with matplotlib's Agg backend into files."""

from __future__ import annotations

import functools
import math
import textwrap
from collections.abc import Callable
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from casadi_posture.biomech.curve import TorqueCurve
from casadi_posture.data.parameters import data_name
from casadi_posture.ergonomics.posture_scores import body_kind
from casadi_posture.ik.tasks import Line, Plane, Position
from casadi_posture.output.figures3d import plot_postures_3d
from casadi_posture.output.key_postures import key_postures, recoveries, title
from casadi_posture.output.low_back import step_low_back
from casadi_posture.output.low_back_plots import plot_low_back
from casadi_posture.output.saving import lay_out, save_figure
from casadi_posture.output.schedule_plots import plot_schedule
from casadi_posture.output.score_plots import plot_scores
from casadi_posture.output.skeleton import Skeleton
from casadi_posture.output.time_axis import in_unit, time_unit
from casadi_posture.simulation import SimulationResult


def figure_formats() -> list[str]:
    """The file endings a figure can be saved with (without the dot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    return sorted(FigureCanvasAgg.get_supported_filetypes())


def plot_torque_curve(curve: TorqueCurve, path: Path, title: str) -> Path:
    """The paper's Fig. 3: passive, external, active and minus-active torque over the range."""
    deg = np.degrees(curve.angles)
    fig = Figure(figsize=(7.0, 4.5), dpi=120)
    ax = fig.subplots()
    ax.axhline(0.0, color="0.6", lw=0.8)
    ax.plot(deg, curve.passive, color="tab:blue", lw=2, label="passive τp")
    ax.plot(deg, curve.external, color="black", lw=1.5, label="external τe")
    ax.plot(deg, curve.active, color="tab:red", lw=2, label="active τa = -(τp + τe)")
    ax.plot(deg, -curve.active, color="tab:red", lw=1.2, ls="--", label="-τa")
    for zero in curve.zeros:
        ax.axvline(np.degrees(zero.angle), color="tab:green", lw=0.8, ls=":")
        ax.plot(np.degrees(zero.angle), 0.0, "o", color="tab:green")
    span = max(np.max(np.abs(curve.external)), 1.0) * 2.5
    ax.set_ylim(-span, span)
    ax.set_xlim(deg[0], deg[-1])
    ax.set_xlabel(f"{curve.dof} (deg)")
    ax.set_ylabel("torque (N·m)")
    ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    return save_figure(fig, path)


#: Loaded groups whose legend fits inside fatigue.png's axes.
INSIDE_LEGEND = 6

#: A group gets a line in fatigue.png when its fatigue passes this level (1 %).
DRAWN_MIN_FATIGUE = 0.01


def plot_fatigue(result: SimulationResult, path: Path) -> Path:
    """Fatigue of every half-joint above 1 % over time with both thresholds (paper Fig. 9):
    a group's right and left sides in one colour, the left dashed (and said so where they
    coincide); more than ``INSIDE_LEGEND`` groups get a legend beside the axes."""
    tl, s = result.timeline, result.settings
    halves = result.problem.body.half_joints
    peak = tl.fatigue.max(axis=0) if tl.fatigue.size else np.zeros(len(halves))
    drawn = [k for k in range(len(halves)) if peak[k] >= DRAWN_MIN_FATIGUE]
    drawn = drawn or [k for k in range(len(halves)) if peak[k] > 0]
    many = len(drawn) > INSIDE_LEGEND
    fig = Figure(figsize=(9.5 if many else 7.0, 4.0), dpi=120)
    ax = fig.subplots()
    colours = matplotlib.colormaps["tab10"].colors
    groups = list(dict.fromkeys(data_name(halves[k].name) for k in drawn))
    same = []
    scale, unit = time_unit(tl.time)
    for k in drawn:
        name = halves[k].name
        left = name.endswith("_l")
        ax.plot(
            tl.time / scale,
            tl.fatigue[:, k],
            lw=1.4 if left else 2.0,
            ls="--" if left else "-",
            color=colours[groups.index(data_name(name)) % len(colours)],
            label=name,
        )
        mirror = name[:-2] + "_r" if left else None
        others = [j for j in drawn if halves[j].name == mirror]
        if others and np.allclose(tl.fatigue[:, k], tl.fatigue[:, others[0]], atol=1e-6):
            same.append(data_name(name))
    over = [e for e in result.events if e.kind == "over_strength"]
    if over:
        ax.plot(
            [e.time_s / scale for e in over],
            [1.0] * len(over),
            "x",
            color="tab:red",
            ms=10,
            mew=2,
            label="over strength: exhausted at once",
        )
    ax.axhline(s.fatigue_threshold, color="tab:red", ls=":", lw=1, label="fatigue threshold")
    ax.axhline(s.recovery_threshold, color="tab:green", ls=":", lw=1, label="recovery threshold")
    active = tl.owner >= 0
    if active.any():
        ax.fill_between(
            tl.time / scale, 0, 1.05, where=active, color="0.85", step="post", label="constraint on"
        )
    ax.set_ylim(0, 1.05)
    ax.set_xlabel(f"time ({unit})")
    ax.set_ylabel("fatigue level")
    ax.set_title(title(result))
    below = sum(1 for k in range(len(halves)) if 0 < peak[k] < DRAWN_MIN_FATIGUE)
    notes = [f"left and right coincide: {', '.join(same)}"] if same else []
    if below and len(drawn) < len(halves):
        notes.append(f"{below} more loaded groups stay below 1 % fatigue")
    if notes:
        fig.text(0.01, 0.01, "; ".join(notes), fontsize=7, color="0.3")
    if many:
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    else:
        ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    return save_figure(fig, path)


#: A body region gets a panel in fatigue_regions.png when one of its groups passes this
#: fatigue level (1 %); a group gets a line when it does.
REGION_MIN_FATIGUE = 0.01


def _regions(result: SimulationResult) -> dict[str, list[int]]:
    """The half-joints of each body region, regions in the body's order."""
    regions: dict[str, list[int]] = {}
    for k, half in enumerate(result.problem.body.half_joints):
        regions.setdefault(half.region, []).append(k)
    return regions


def fatigue_regions_figure(result: SimulationResult) -> Figure:
    """Fatigue over time (min, or s for a run of 5 min or less), one panel (labelled with its
    region) per body region that has a group above 1 % fatigue (at least the most tired
    region's), the region that
    reached the fatigue threshold first on top, then by largest fatigue; both thresholds,
    when a group of the region owned the constraint, and where each group first reached
    the fatigue threshold."""
    tl, s = result.timeline, result.settings
    halves = result.problem.body.half_joints
    times, unit = in_unit(tl.time)
    peak = tl.fatigue.max(axis=0)
    reached = tl.fatigue >= s.fatigue_threshold
    first = np.where(reached.any(axis=0), times[np.argmax(reached, axis=0)], np.inf)
    regions = _regions(result)
    tired = {r: ks for r, ks in regions.items() if peak[ks].max() > REGION_MIN_FATIGUE}
    if not tired:
        top = halves[int(np.argmax(peak))].region
        tired = {top: regions[top]}
    order = sorted(tired, key=lambda r: (first[tired[r]].min(), -peak[tired[r]].max()))
    height = 1.2 + 1.8 * len(order)  # [in]
    fig = Figure(figsize=(9.0, height), dpi=120)
    axes = fig.subplots(len(order), 1, sharex=True, squeeze=False)
    for ax, region in zip(axes[:, 0], order, strict=True):
        groups = [k for k in tired[region] if peak[k] > REGION_MIN_FATIGUE]
        groups = groups or [max(tired[region], key=lambda k: peak[k])]
        for k in groups:
            (line,) = ax.plot(times, tl.fatigue[:, k], lw=1.6, label=halves[k].name)
            if np.isfinite(first[k]):
                ax.plot(first[k], s.fatigue_threshold, "o", ms=5, color=line.get_color())
        ax.axhline(s.fatigue_threshold, color="tab:red", ls="--", lw=1)
        ax.axhline(s.recovery_threshold, color="tab:green", ls="--", lw=1)
        owned = np.isin(tl.owner, tired[region])
        if owned.any():
            ax.fill_between(times, 0, 1.05, where=owned, color="0.88", step="post", zorder=0)
        earliest = min(tired[region], key=lambda k: (first[k], -peak[k]))
        if np.isfinite(first[earliest]):
            when = f"{first[earliest]:.1f} min" if unit == "min" else f"{first[earliest]:g} s"
            note = f"first at the threshold {halves[earliest].name}, {when}"
        else:
            note = f"largest fatigue {peak[earliest]:.2f} ({halves[earliest].name})"
        ax.set_title(f"{region} — {note}", fontsize=9, loc="left")
        ax.set_label(region)
        ax.set_ylim(0, 1.05)
        ax.set_ylabel("fatigue level", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        columns = 1 + len(groups) // 7
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5), ncol=columns)
    axes[-1, 0].set_xlabel(f"time ({unit})", fontsize=8)
    shared = [
        Line2D([], [], color="tab:red", ls="--", lw=1, label="fatigue threshold"),
        Line2D([], [], color="tab:green", ls="--", lw=1, label="recovery threshold"),
        Patch(color="0.88", label="constraint owned by a group of the region"),
        Line2D(
            [], [], ls="", marker="o", ms=5, color="0.3", label="first at the fatigue threshold"
        ),
    ]
    fig.suptitle(title(result), fontsize=10, y=1 - 0.2 / height)
    fig.legend(
        handles=shared,
        loc="upper center",
        ncol=4,
        fontsize=7,
        frameon=False,
        bbox_to_anchor=(0.5, 1 - 0.42 / height),
    )
    quiet = [r for r in regions if r not in tired]
    if quiet:
        below = f"below {100 * REGION_MIN_FATIGUE:g} % fatigue throughout: {', '.join(quiet)}"
        fig.text(0.01, 0.1 / height, below, fontsize=7)
    lay_out(fig, rect=(0, 0.25 / height, 1, 1 - 0.55 / height))
    return fig


def plot_fatigue_regions(result: SimulationResult, path: Path) -> Path:
    """``fatigue_regions_figure`` into ``path``."""
    return save_figure(fatigue_regions_figure(result), path, tight=False)


def _draw_tasks(ax: Axes, result: SimulationResult, skeleton: Skeleton) -> None:
    """Lines, planes (their trace in the plane of motion) and target points of the tasks."""
    i, j = skeleton.plane
    ax.autoscale(False)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    span = 2 * max(x1 - x0, y1 - y0)
    for task in result.tasks:
        if isinstance(task, Line):
            d = np.asarray(task.direction) / np.linalg.norm(task.direction)
            ends = np.asarray(task.point) + np.outer([-span, span], d)
            ax.plot(ends[:, i], ends[:, j], color="0.45", lw=1, ls="--", label=task.name)
        elif isinstance(task, Plane):
            n = np.asarray(task.normal) / np.linalg.norm(task.normal)
            if math.hypot(n[i], n[j]) < 1e-9:
                continue
            along = np.array([-n[j], n[i]]) / math.hypot(n[i], n[j])
            centre = np.array([task.point[i], task.point[j]])
            ends = centre + np.outer([-span, span], along)
            ax.plot(ends[:, 0], ends[:, 1], color="0.45", lw=1, ls=":", label=task.name)
        elif isinstance(task, Position):
            ax.plot(
                task.target[i], task.target[j], "x", color="black", ms=9, mew=2, label=task.name
            )


def _mark_cycles(ax: Axes, result: SimulationResult) -> None:
    """Shade the intervals the fatigue constraint was on; mark each recovery."""
    tl = result.timeline
    scale, _ = time_unit(tl.time)
    on = tl.owner >= 0
    if on.any():
        low, high = ax.get_ylim()
        ax.fill_between(
            tl.time / scale,
            low,
            high,
            where=on,
            color="0.88",
            step="post",
            label="constraint on",
            zorder=0,
        )
        ax.set_ylim(low, high)
    for k, step in enumerate(recoveries(result)):
        ax.axvline(
            tl.time[step] / scale,
            color="tab:green",
            lw=1,
            ls="--",
            label="recovered (fatigue 0.5)" if k == 0 else None,
        )


def _at_least(ax: Axes, span: float) -> None:
    """Widen the y-axis about its middle to at least ``span``."""
    low, high = ax.get_ylim()
    if high - low < span:
        middle = (low + high) / 2
        ax.set_ylim(middle - span / 2, middle + span / 2)


#: Joint angles drawn in effector.png when no line or point task is followed: those that
#: move most.
DRAWN_ANGLES = 6

#: Motion below which a figure says the joint did not move [deg].
STILL_DEG = 0.1


def _say(ax: Axes, text: str) -> None:
    """Write ``text`` in the middle of ``ax``: what a degenerate plot does not show."""
    ax.text(
        0.5, 0.5, textwrap.fill(text, 48), transform=ax.transAxes, ha="center", va="center",
        fontsize=9,
        color="0.25", bbox={"facecolor": "white", "edgecolor": "0.7", "alpha": 0.9},
    )  # fmt: skip


def _level(result: SimulationResult, task: object) -> int:
    """The index of ``task``'s priority level among the run's levels (the residual column)."""
    priorities = sorted({t.priority for t in result.tasks})
    return priorities.index(task.priority)


def plot_effector(result: SimulationResult, path: Path) -> Path:
    """The task followed over time (paper Figs 12–14): the effector's position along the
    first line task; else the top task's distance to its target point or plane; else (no
    such task, or none: a recording) the joint angles that move most; the fatigue/recovery
    cycles marked. A distance axis spans at least 1 mm, so that rounding noise does not look
    like motion."""
    tl = result.timeline
    ordered = sorted(result.tasks, key=lambda t: t.priority)
    line = next((t for t in ordered if isinstance(t, Line)), None)
    top = next((t for t in ordered if isinstance(t, Position | Plane)), None)
    fig = Figure(figsize=(7.0, 3.6), dpi=120)
    ax = fig.subplots()
    times, unit = in_unit(tl.time)
    if line is not None and tl.along_line is not None:
        ax.plot(times, tl.along_line, color="tab:blue", lw=1.8)
        ax.set_ylabel(f"{line.effector} along the line (m)")
        _at_least(ax, 1e-3)
    elif isinstance(top, Position | Plane):
        ax.plot(times, tl.residuals[:, _level(result, top)], color="tab:blue", lw=1.8)
        kind = "target" if isinstance(top, Position) else "plane"
        ax.set_ylabel(f"{top.effector} to the {kind} (m)")
        _at_least(ax, 1e-3)
    else:
        dofs = result.problem.body.dofs
        motion = np.degrees(np.ptp(tl.q, axis=0))
        moving = np.argsort(-motion, kind="stable")[:DRAWN_ANGLES]
        for i in sorted(moving):
            ax.plot(times, np.degrees(tl.q[:, i]), lw=1.8, label=dofs[i].name)
        most = f", the {DRAWN_ANGLES} that move most" if len(dofs) > DRAWN_ANGLES else ""
        ax.set_ylabel(f"joint angle (deg){most}")
        if motion.max() < STILL_DEG:
            _say(ax, f"no joint moved more than {STILL_DEG:g}° during the run")
    ax.set_xlabel(f"time ({unit})")
    ax.set_title(title(result))
    ax.grid(alpha=0.3)
    _mark_cycles(ax, result)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="best")
    return save_figure(fig, path)


def _owner_dof(result: SimulationResult) -> int:
    """The DOF of the first half-joint that owned the constraint, or of the most loaded."""
    tl, body = result.timeline, result.problem.body
    owners = tl.owner[tl.owner >= 0]
    group = int(owners[0]) if owners.size else int(np.argmax(tl.load[0]))
    return body.half_joints[group].dof_index


def plot_active_torque(result: SimulationResult, path: Path) -> Path:
    """The paper's Figs 15–17: the fatigued joint's active torque against its angle over the
    run, from the initial posture to the goal (the first recovery, or the end), with both
    postures drawn."""
    tl, body = result.timeline, result.problem.body
    j = _owner_dof(result)
    steps = recoveries(result)
    goal = steps[0] if steps else tl.time.size - 1
    skeleton = Skeleton(body, tl.q)
    fig = Figure(figsize=(9.0, 4.2), dpi=120)
    ax = fig.add_axes((0.08, 0.13, 0.55, 0.75))
    deg = np.degrees(tl.q[:, j])
    ax.axhline(0, color="0.6", lw=0.8)
    ax.plot(
        deg[: goal + 1],
        tl.active[: goal + 1, j],
        color="tab:red",
        lw=1.5,
        label="active torque, initial to goal",
    )
    if goal + 1 < deg.size:
        ax.plot(deg[goal:], tl.active[goal:, j], color="0.7", lw=0.8, label="after the goal")
    ax.plot(deg[0], tl.active[0, j], "o", color="black", ms=7, label=f"initial ({tl.time[0]:g} s)")
    name = f"recovery ({tl.time[goal]:g} s)" if steps else f"end ({tl.time[goal]:g} s)"
    ax.plot(deg[goal], tl.active[goal, j], "s", color="tab:green", ms=7, label=name)
    ax.set_xlabel(f"{body.dofs[j].name} (deg)")
    ax.set_ylabel("active torque (N·m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(title(result), fontsize=9)
    if np.ptp(deg[: goal + 1]) < STILL_DEG:
        _say(
            ax,
            f"{body.dofs[j].name} did not move from the initial posture to the "
            f"{name.split(' (')[0]}: nothing to trace",
        )
    for k, (step, color, label) in enumerate(
        ((0, "black", "initial"), (goal, "tab:green", name.split(" (")[0]))
    ):
        inset = fig.add_axes((0.70, 0.58 - 0.46 * k, 0.28, 0.31))
        skeleton.draw(inset, step, color=color, lw=2)
        skeleton.frame(inset)
        skeleton.fit(inset)
        inset.set_title(label, fontsize=8)
        inset.tick_params(labelsize=6)
        inset.xaxis.label.set_size(7)
        inset.yaxis.label.set_size(7)
    return save_figure(fig, path, tight=False)


def plot_postures(result: SimulationResult, path: Path) -> Path:
    """Stick figures in the plane the body moves in: the initial posture, each recovery
    posture (the first few, told apart by colour and time) and the last one; the tasks'
    lines, planes and targets drawn."""
    skeleton = Skeleton(result.problem.body, result.timeline.q)
    fig = Figure(figsize=(6.0, 5.0), dpi=120)
    ax = fig.subplots()
    for k, (step, label, colour) in enumerate(key_postures(result)):
        skeleton.draw(ax, step, color=colour, lw=2.6 if k == 0 else 1.6, label=label)
    skeleton.frame(ax)
    skeleton.fit(ax)
    _draw_tasks(ax, result, skeleton)
    ax.set_title(title(result), fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    ax.legend(unique.values(), unique.keys(), fontsize=7, loc="best")
    return save_figure(fig, path)


def simulation_figures(result: SimulationResult, out: Path) -> dict[str, Callable[[], Path]]:
    """Each figure of a simulation into ``out`` by its file's name, to be drawn (none for a
    run stopped before its first step): postures.png in the plane of motion for a planar
    body, in four views for a 3-D one; fatigue_regions.png for a body of more than one
    region; schedule.png for a run with a work–rest schedule; scores.png (RULA and REBA)
    for a body they fit; low_back.png (compression and shear at L5/S1) for a body with a
    lumbar joint. Each draws on its own, in any order or process."""
    if result.timeline.time.size == 0:
        return {}
    body = result.problem.body
    draw_postures = plot_postures if body.planar else plot_postures_3d
    figures = [
        (plot_fatigue, "fatigue.png"),
        (plot_effector, "effector.png"),
        (plot_active_torque, "active_torque.png"),
        (draw_postures, "postures.png"),
    ]
    if len(_regions(result)) > 1:
        figures.append((plot_fatigue_regions, "fatigue_regions.png"))
    if result.schedule is not None:
        figures.append((plot_schedule, "schedule.png"))
    if body_kind(body) is not None:
        figures.append((plot_scores, "scores.png"))
    drawn = {name: functools.partial(draw, result, out / name) for draw, name in figures}
    back = step_low_back(result)
    if back is not None:
        drawn["low_back.png"] = functools.partial(plot_low_back, result, back, out / "low_back.png")
    return drawn
