"""A population run's figures: the share of each sex still holding the task over time, and
each worker's time held against their stature."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from casadi_posture.biomech.capability import PEOPLE, SEXES
from casadi_posture.output.saving import save_figure
from casadi_posture.output.time_axis import time_unit
from casadi_posture.people.statistics import wilson

COLOURS = {"male": "tab:blue", "female": "tab:red"}


def _figure(
    rows: Sequence[Mapping[str, Any]],
) -> tuple[Figure, Axes, float, str, dict[str, list[Mapping[str, Any]]]]:
    """A figure and its axes, the time unit of the runs (``time_unit``: its divisor from s
    and its name) and the rows of the workers that ran, per sex (none: left out)."""
    ran = {
        sex: [r for r in rows if r.get("body.sex") == sex and r.get("status") in ("ok", "flagged")]
        for sex in SEXES
    }
    ran = {sex: found for sex, found in ran.items() if found}
    ends = [float(r["simulated_s"]) for found in ran.values() for r in found]
    scale, unit = time_unit(np.array([0.0, max(ends, default=1.0)]))
    fig = Figure(figsize=(7.0, 4.0), dpi=120)
    ax = fig.subplots()
    return fig, ax, scale, unit, ran


def survival_steps(held: np.ndarray, still: np.ndarray, end: float) -> tuple[np.ndarray, list[int]]:
    """The steps of a survival curve: the times [s] at which it changes (0, each time held
    before ``end``, ``end``) and how many of the times ``held`` [s] are still holding just
    after each (one held 0 s never held); at ``end`` itself, those whose run ended with
    the task still held (``still``)."""
    times = np.unique(np.concatenate([[0.0], held[held < end], [end]]))
    counts = [int((held > t + 1e-9).sum()) for t in times[:-1]]
    return times, [*counts, int((still & (held >= end - 1e-9)).sum())]


def plot_survival(rows: Sequence[Mapping[str, Any]], path: Path, title: str) -> Path:
    """survival.png: per sex, the share of workers still holding the task against time
    (``survival_steps``: a step down at each worker's time held, at once for one who never
    held it; a run that ended with the task held stays up to its end), with its Wilson
    95 % band."""
    fig, ax, scale, unit, workers = _figure(rows)
    for sex, ran in workers.items():
        held = np.array([float(r["task_held_s"]) for r in ran])
        still = np.array([bool(r["task_held_is_lower_bound"]) for r in ran])
        end = max(float(r["simulated_s"]) for r in ran)
        times, counts = survival_steps(held, still, end)
        share = np.array(counts) / len(ran)
        band = np.array([wilson(count, len(ran)) for count in counts])
        label = f"{PEOPLE[sex]} (n = {len(ran)})"
        ax.step(times / scale, 100 * share, where="post", color=COLOURS[sex], lw=2, label=label)
        low, high = 100 * band[:, 0], 100 * band[:, 1]
        ax.fill_between(times / scale, low, high, step="post", color=COLOURS[sex], alpha=0.15)
    ax.set_ylim(0, 102)
    ax.set_xlabel(f"time ({unit})")
    ax.set_ylabel("still holding the task (%)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, title="shaded: 95 % interval", title_fontsize=7)
    return save_figure(fig, path)


def plot_held_vs_stature(rows: Sequence[Mapping[str, Any]], path: Path, title: str) -> Path:
    """held_vs_stature.png: each worker's time held against their stature, per sex; a
    hollow marker where the run ended with the task still held (a lower bound)."""
    fig, ax, scale, unit, workers = _figure(rows)
    for sex, ran in workers.items():
        stature = np.array([float(r["body.stature_m"]) for r in ran])
        held = np.array([float(r["task_held_s"]) for r in ran]) / scale
        open_ = np.array([bool(r["task_held_is_lower_bound"]) for r in ran])
        if (~open_).any():
            ax.scatter(stature[~open_], held[~open_], s=14, color=COLOURS[sex], label=PEOPLE[sex])
        if open_.any():
            label = f"{PEOPLE[sex]}: held to the end"
            ax.scatter(stature[open_], held[open_], s=14, facecolors="none",
                       edgecolors=COLOURS[sex], label=label)  # fmt: skip
    ax.set_xlabel("stature (m)")
    ax.set_ylabel(f"task held ({unit})")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)
