"""Figures, drawn with matplotlib's Agg backend into files."""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from casadi_posture.biomech.curve import TorqueCurve
from casadi_posture.ik.tasks import Line, Plane, Position
from casadi_posture.simulation import SimulationResult


def figure_formats() -> list[str]:
    """The file endings a figure can be saved with (without the dot)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    return sorted(FigureCanvasAgg.get_supported_filetypes())


def plot_torque_curve(curve: TorqueCurve, path: Path, title: str) -> Path:
    """The paper's Fig. 3: passive, external, active and minus-active torque over the range."""
    deg = np.degrees(curve.angles)
    fig, ax = plt.subplots(figsize=(7.0, 4.5), dpi=120)
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
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


#: Recovery postures drawn in postures.png (summary.json lists them all).
DRAWN_RECOVERIES = 5


def _title(result: SimulationResult) -> str:
    text = f"{result.problem.path.stem}: {result.settings.strategy} strategy, {result.solver}"
    if result.stop == "interrupted":
        text += " (interrupted: partial run)"
    elif result.stop == "never_held":
        text += " (task never held)"
    return text


def plot_fatigue(result: SimulationResult, path: Path) -> Path:
    """Fatigue of every loaded half-joint over time with both thresholds (paper Fig. 9)."""
    tl, s = result.timeline, result.settings
    fig, ax = plt.subplots(figsize=(7.0, 4.0), dpi=120)
    for k, half in enumerate(result.problem.body.half_joints):
        if tl.fatigue[:, k].max() > 0:
            ax.plot(tl.time / 60, tl.fatigue[:, k], lw=1.8, label=half.name)
    over = [e for e in result.events if e.kind == "over_strength"]
    if over:
        ax.plot(
            [e.time_s / 60 for e in over],
            [1.0] * len(over),
            "x",
            color="tab:red",
            ms=10,
            mew=2,
            label="over strength: exhausted at once",
        )
    ax.axhline(s.fatigue_threshold, color="tab:red", ls="--", lw=1, label="fatigue threshold")
    ax.axhline(s.recovery_threshold, color="tab:green", ls="--", lw=1, label="recovery threshold")
    active = tl.owner >= 0
    if active.any():
        ax.fill_between(
            tl.time / 60, 0, 1.05, where=active, color="0.85", step="post", label="constraint on"
        )
    ax.set_ylim(0, 1.05)
    ax.set_xlabel("time (min)")
    ax.set_ylabel("fatigue level")
    ax.set_title(_title(result))
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    return _save(fig, path)


#: World axes and their labels.
_AXES = {0: "x forward (m)", 1: "y left (m)", 2: "z up (m)"}


class _Skeleton:
    """The body as stick figures over time: each segment from its proximal to its distal
    landmark when every segment names them, else the tree itself (each joint centre joined
    to its parent's, each landmark to the joint centre that carries it)."""

    def __init__(self, result: SimulationResult) -> None:
        body = result.problem.body
        named = all(s.proximal and s.distal for s in body.segments)
        if named:
            ends = [(s.proximal, s.distal) for s in body.segments if s.proximal != s.distal]
            expressions = {n: body.landmark(n) for pair in ends for n in pair}
        else:
            centres = {d.name: body.point(d.name, d.origin) for d in body.dofs}
            ends = [(d.parent, d.name) for d in body.dofs if d.parent is not None]
            ends += [(lm.dof, lm.name) for lm in body.landmarks.values() if lm.dof is not None]
            expressions = centres | {n: body.landmark(n) for n in body.landmarks}
        self.names = list(expressions)
        self.bones = [(self.names.index(a), self.names.index(b)) for a, b in ends]
        points = ca.horzcat(*expressions.values())
        function = ca.Function("points", [body.q], [points]).map(max(result.timeline.time.size, 1))
        q = result.timeline.q.T if result.timeline.time.size else np.zeros((body.n, 1))
        stacked = np.asarray(function(q))  # 3 × (landmarks·steps)
        self.points = stacked.reshape(3, -1, len(self.names)).transpose(1, 0, 2)
        spread = np.ptp(self.points.transpose(1, 0, 2).reshape(3, -1), axis=1)
        self.plane = tuple(sorted(int(i) for i in np.argsort(spread)[-2:]))
        self.depth = next(i for i in range(3) if i not in self.plane)

    def draw(self, ax: plt.Axes, step: int, **style: object) -> None:
        """The stick figure at ``step`` in the plane of motion."""
        i, j = self.plane
        xyz = self.points[step]
        for a, b in self.bones:
            ax.plot([xyz[i, a], xyz[i, b]], [xyz[j, a], xyz[j, b]], "-", **style)
        ax.plot(xyz[i], xyz[j], "o", ms=4, color=style.get("color"))

    def frame(self, ax: plt.Axes) -> None:
        ax.set_aspect("equal")
        ax.set_xlabel(_AXES[self.plane[0]])
        ax.set_ylabel(_AXES[self.plane[1]])
        ax.grid(alpha=0.3)


def _draw_tasks(ax: plt.Axes, result: SimulationResult, skeleton: _Skeleton) -> None:
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


def _recoveries(result: SimulationResult) -> list[int]:
    """Steps at which the constraint was released (recovery postures)."""
    tl = result.timeline
    return [
        int(np.argmax(tl.time >= e.time_s)) for e in result.events if e.kind == "constraint_off"
    ]


def _mark_cycles(ax: plt.Axes, result: SimulationResult) -> None:
    """Shade the intervals the fatigue constraint was on; mark each recovery."""
    tl = result.timeline
    on = tl.owner >= 0
    if on.any():
        low, high = ax.get_ylim()
        ax.fill_between(
            tl.time / 60,
            low,
            high,
            where=on,
            color="0.88",
            step="post",
            label="constraint on",
            zorder=0,
        )
        ax.set_ylim(low, high)
    for k, step in enumerate(_recoveries(result)):
        ax.axvline(
            tl.time[step] / 60,
            color="tab:green",
            lw=1,
            ls="--",
            label="recovered (fatigue 0.5)" if k == 0 else None,
        )


def plot_effector(result: SimulationResult, path: Path) -> Path:
    """The top task over time (paper Figs 12–14): the effector's position along a line, its
    distance to a target point or a plane, or the joint angles of a posture task; the
    fatigue/recovery cycles marked."""
    tl = result.timeline
    top = next(t for t in result.tasks if t.priority == min(x.priority for x in result.tasks))
    fig, ax = plt.subplots(figsize=(7.0, 3.6), dpi=120)
    minutes = tl.time / 60
    if isinstance(top, Line) and tl.along_line is not None:
        ax.plot(minutes, tl.along_line, color="tab:blue", lw=1.8)
        ax.set_ylabel(f"{top.effector} along the line (m)")
    elif isinstance(top, Position | Plane):
        ax.plot(minutes, tl.residuals[:, 0], color="tab:blue", lw=1.8)
        kind = "target" if isinstance(top, Position) else "plane"
        ax.set_ylabel(f"{top.effector} to the {kind} (m)")
    else:
        for i, dof in enumerate(result.problem.body.dofs):
            ax.plot(minutes, np.degrees(tl.q[:, i]), lw=1.8, label=dof.name)
        ax.set_ylabel("joint angle (deg)")
    ax.set_xlabel("time (min)")
    ax.set_title(_title(result))
    ax.grid(alpha=0.3)
    _mark_cycles(ax, result)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="best")
    return _save(fig, path)


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
    recoveries = _recoveries(result)
    goal = recoveries[0] if recoveries else tl.time.size - 1
    skeleton = _Skeleton(result)
    fig = plt.figure(figsize=(9.0, 4.2), dpi=120)
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
    name = f"recovery ({tl.time[goal]:g} s)" if recoveries else f"end ({tl.time[goal]:g} s)"
    ax.plot(deg[goal], tl.active[goal, j], "s", color="tab:green", ms=7, label=name)
    ax.set_xlabel(f"{body.dofs[j].name} (deg)")
    ax.set_ylabel("active torque (N·m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(_title(result), fontsize=9)
    for k, (step, color, label) in enumerate(
        ((0, "black", "initial"), (goal, "tab:green", name.split(" (")[0]))
    ):
        inset = fig.add_axes((0.70, 0.58 - 0.46 * k, 0.28, 0.31))
        skeleton.draw(inset, step, color=color, lw=2)
        skeleton.frame(inset)
        _fit(inset, skeleton)
        inset.set_title(label, fontsize=8)
        inset.tick_params(labelsize=6)
        inset.xaxis.label.set_size(7)
        inset.yaxis.label.set_size(7)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path


def _fit(ax: plt.Axes, skeleton: _Skeleton) -> None:
    """Axis limits around every posture of the run, with a margin."""
    i, j = skeleton.plane
    xs, ys = skeleton.points[:, i].ravel(), skeleton.points[:, j].ravel()
    margin = 0.08 * max(np.ptp(xs), np.ptp(ys), 0.1)
    ax.set_xlim(xs.min() - margin, xs.max() + margin)
    ax.set_ylim(ys.min() - margin, ys.max() + margin)


def _merge_repeats(
    shown: list[tuple[int, str, object]], q: np.ndarray, tolerance_deg: float = 0.5
) -> list[tuple[int, str, object]]:
    """One stick figure per distinct posture: postures within ``tolerance_deg`` of an earlier
    one add their label to it (a cycle that recovers where it recovered before)."""
    merged: list[tuple[int, str, object]] = []
    for step, label, colour in shown:
        same = next(
            (
                k
                for k, (other, _, _) in enumerate(merged)
                if np.max(np.abs(np.degrees(q[step] - q[other]))) < tolerance_deg
            ),
            None,
        )
        if same is None:
            merged.append((step, label, colour))
        else:
            first, text, first_colour = merged[same]
            merged[same] = (first, f"{text}; {label}", first_colour)
    return merged


def plot_postures(result: SimulationResult, path: Path) -> Path:
    """Stick figures in the plane the body moves in: the initial posture, each recovery
    posture (the first few, told apart by colour and time) and the last one; the tasks'
    lines, planes and targets drawn."""
    tl = result.timeline
    skeleton = _Skeleton(result)
    recoveries = _recoveries(result)
    shown = [(0, "initial", "black")]
    colours = plt.cm.viridis(np.linspace(0.15, 0.85, max(len(recoveries[:DRAWN_RECOVERIES]), 1)))
    for step, colour in zip(recoveries[:DRAWN_RECOVERIES], colours, strict=False):
        shown.append((step, f"recovery at {tl.time[step]:g} s", colour))
    if len(recoveries) > DRAWN_RECOVERIES:
        step, label, colour = shown[-1]
        shown[-1] = (step, f"{label} (+{len(recoveries) - DRAWN_RECOVERIES} more)", colour)
    shown.append((tl.time.size - 1, f"end ({tl.time[-1]:g} s)", "tab:red"))
    fig, ax = plt.subplots(figsize=(6.0, 5.0), dpi=120)
    for k, (step, label, colour) in enumerate(_merge_repeats(shown, tl.q)):
        skeleton.draw(ax, step, color=colour, lw=2.6 if k == 0 else 1.6, label=label)
    skeleton.frame(ax)
    _fit(ax, skeleton)
    _draw_tasks(ax, result, skeleton)
    ax.set_title(_title(result), fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    ax.legend(unique.values(), unique.keys(), fontsize=7, loc="best")
    return _save(fig, path)


def plot_simulation(result: SimulationResult, out: Path) -> list[Path]:
    """All figures of a simulation into ``out`` (none for a run stopped before its first
    step)."""
    if result.timeline.time.size == 0:
        return []
    return [
        plot_fatigue(result, out / "fatigue.png"),
        plot_effector(result, out / "effector.png"),
        plot_active_torque(result, out / "active_torque.png"),
        plot_postures(result, out / "postures.png"),
    ]
