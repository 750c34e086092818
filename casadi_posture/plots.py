"""Figures, drawn with matplotlib's Agg backend into files."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from .curve import TorqueCurve
from .simulation import SimulationResult
from .tasks import Line


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


def plot_effector(result: SimulationResult, path: Path) -> Path:
    """The effector's position along the line over time (paper Figs 12–14), or its height."""
    tl = result.timeline
    fig, ax = plt.subplots(figsize=(7.0, 3.5), dpi=120)
    if tl.along_line is not None:
        ax.plot(tl.time / 60, tl.along_line, color="tab:blue", lw=1.8)
        ax.set_ylabel(f"{result.effector} along the line (m)")
    else:
        ax.plot(tl.time / 60, tl.effector[:, 2], color="tab:blue", lw=1.8)
        ax.set_ylabel(f"{result.effector} height (m)")
    ax.set_xlabel("time (min)")
    ax.set_title(_title(result))
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_active_torque(result: SimulationResult, path: Path) -> Path:
    """Active torque against joint angle along the run, per DOF (paper Figs 15–17)."""
    tl, body = result.timeline, result.problem.body
    fig, axes = plt.subplots(1, body.n, figsize=(4.0 * body.n, 3.8), dpi=120, squeeze=False)
    for i, (ax, dof) in enumerate(zip(axes[0], body.dofs, strict=True)):
        deg = np.degrees(tl.q[:, i])
        ax.plot(deg, tl.active[:, i], color="tab:red", lw=1.2)
        ax.plot(deg[0], tl.active[0, i], "o", color="black", label="initial")
        ax.plot(deg[-1], tl.active[-1, i], "s", color="tab:red", label="end")
        ax.axhline(0, color="0.6", lw=0.8)
        ax.set_xlabel(f"{dof.name} (deg)")
        ax.set_ylabel("active torque (N·m)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(_title(result), fontsize=10)
    return _save(fig, path)


def plot_postures(result: SimulationResult, path: Path) -> Path:
    """Stick figures of the initial posture and of each recovery posture (x-z plane)."""
    tl, body = result.timeline, result.problem.body
    chain = ["shoulder", "elbow", "wrist", "knuckles"]
    points = ca.Function("points", [body.q], [ca.horzcat(*[body.landmark(n) for n in chain])])
    recoveries = [
        int(np.argmax(tl.time >= e.time_s)) for e in result.events if e.kind == "constraint_off"
    ]
    shown = [(0, "initial")] + [
        (k, f"recovery at {tl.time[k]:.0f} s") for k in recoveries[:DRAWN_RECOVERIES]
    ]
    if len(recoveries) > DRAWN_RECOVERIES:
        shown[-1] = (shown[-1][0], f"{shown[-1][1]} (+{len(recoveries) - DRAWN_RECOVERIES} more)")
    shown.append((tl.time.size - 1, f"end ({tl.time[-1]:.0f} s)"))
    fig, ax = plt.subplots(figsize=(5.0, 5.0), dpi=120)
    for j, (step, label) in enumerate(shown):
        xyz = np.asarray(points(tl.q[step]))
        ax.plot(xyz[0], xyz[2], "-o", lw=2.5 if j == 0 else 1.5, label=label)
    for task in result.tasks:
        if isinstance(task, Line):
            d = np.asarray(task.direction) / np.linalg.norm(task.direction)
            ends = np.asarray(task.point) + np.outer([-0.6, 0.6], d)
            ax.plot(ends[:, 0], ends[:, 2], color="0.5", lw=1, ls="--", label=f"{task.name}")
    ax.set_aspect("equal")
    ax.set_xlabel("x forward (m)")
    ax.set_ylabel("z up (m)")
    ax.set_title(_title(result), fontsize=9)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
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
