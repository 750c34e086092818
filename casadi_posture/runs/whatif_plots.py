"""A what-if's figures: one per answer against the first varied axis, one line per value of
the other axes, the axes named in words (output/axes.py)."""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from casadi_posture.biomech.capability import DESIGN_LIMIT_PCT, PEOPLE, SEXES
from casadi_posture.biomech.low_back import limits as back_limits
from casadi_posture.output.axes import axis_value, with_unit
from casadi_posture.output.saving import save_figure
from casadi_posture.output.score_plots import BAND_COLOURS, bands
from casadi_posture.runs.batch import safe_name

#: The answers drawn, with their axis labels; one figure each.
OUTCOMES = {
    "task_held_s": "task held (s)",
    "first_fatigue_s": "first group at the fatigue threshold (s)",
    "fatigue_recovery_cycles": "fatigue/recovery cycles",
    "limiting_endurance_at_start_min": "endurance of the limiting group at the start (min)",
    "capable_pct": "capable of the task at the start (% of each sex)",
    "worst_rula": "worst RULA grand score",
    "worst_reba": "worst REBA score",
    "peak_compression_N": "peak low-back compression at L5/S1 (N)",
}
STATIC_OUTCOMES = (
    "limiting_endurance_at_start_min",
    "capable_pct",
    "worst_rula",
    "worst_reba",
    "peak_compression_N",
)
#: An outcome drawn as several columns of a row, one line each (named in the legend).
SERIES = {"capable_pct": {f"capable_{sex}_pct": PEOPLE[sex] for sex in SEXES}}
#: What an outcome is judged against (dotted lines): the design limit of the share of each
#: sex capable (biomech/capability.py), the NIOSH compression limits (biomech/low_back.py).
LIMITS = {
    "capable_pct": {
        f"{PEOPLE[sex]}: design limit {DESIGN_LIMIT_PCT[sex]:g} % (a convention)": (
            DESIGN_LIMIT_PCT[sex]
        )
        for sex in SEXES
    },
    "peak_compression_N": {
        f"NIOSH {name} limit {value:g} N": value for name, value in back_limits().items()
    },
}
#: Scores drawn over their worksheet's action levels (output/score_plots.py).
SHEETS = {"worst_rula": "rula", "worst_reba": "reba"}
#: How far apart lines of integer scores are drawn [score], so that equal ones show.
SCORE_OFFSET = 0.08


def plot_outcomes(
    rows: Sequence[dict[str, Any]],
    varies: Sequence[tuple[str, list[Any]]],
    labels: Mapping[str, tuple[str, str]],
    out: Path,
    *,
    simulate: bool,
    paired: bool = False,
) -> list[Path]:
    """One figure per answer the rows carry: the answer against the first varied axis, one
    line per combination of the other axes' values (``paired``: one line, each point
    labelled with the other axes' values; the share capable: one line per sex too, with
    its design limit dotted). ``labels`` names each axis in words with its unit.
    Flagged cases (level 1 not reached, over strength, a solver failure) are crossed out
    in red; a task held to the end of the run is a lower bound, drawn as an upward
    triangle."""
    outcomes = OUTCOMES if simulate else {k: OUTCOMES[k] for k in STATIC_OUTCOMES}
    ran = [r for r in rows if r["status"] in ("ok", "flagged")]
    (axis, values), others = varies[0], varies[1:]
    groups = [()] if paired else list(itertools.product(*(v for _, v in others)))
    paths = []
    for outcome, label in outcomes.items():
        series = SERIES.get(outcome, {outcome: ""})
        if not any(r.get(column) is not None for r in ran for column in series):
            continue
        fig = Figure(figsize=(6.4, 4.2), dpi=110)
        ax = fig.subplots()
        for (g, group), (s, (column, sex)) in itertools.product(
            enumerate(groups), enumerate(series.items())
        ):
            members = [r for r in ran if paired or _in_group(r, others, group)]
            if not members:
                continue
            members.sort(key=lambda r: _position(r, axis, values))
            xs = np.array([_position(r, axis, values) for r in members], dtype=float)
            ys = np.array([_number(r.get(column)) for r in members])
            if outcome in SHEETS:  # integer scores: coinciding lines drawn apart
                ys += SCORE_OFFSET * (g - (len(groups) - 1) / 2)
            shown = zip([] if paired else others, group, strict=True)
            name = ", ".join([sex] * bool(sex) + [_given(labels[a], v) for (a, _), v in shown])
            style = ("-o", "--s")[s % 2]  # one colour per combination, one style per sex
            ax.plot(xs, ys, style, color=f"C{g % 10}", label=name or None)
            _marks(ax, outcome, xs, ys, members, f"C{g % 10}")
            if paired and s == 0:
                for x, y, r in zip(xs, ys, members, strict=True):
                    given = ", ".join(_given(labels[a], axis_value(r, a)) for a, _ in others)
                    ax.annotate(given, (x, y), (4, 4), textcoords="offset points", fontsize=6)
        if outcome == "task_held_s" and any(r.get("task_held_is_lower_bound") for r in ran):
            ax.plot([], [], "^", mfc="none", color="0.3", label="held to the end (lower bound)")
        if any(r["status"] == "flagged" for r in ran):
            ax.plot([], [], "x", mew=2, color="tab:red", label="flagged: see whatif.csv")
        _limits(ax, outcome)
        if outcome in SHEETS and len(groups) > 1:
            note = f"lines drawn {SCORE_OFFSET:g} apart where they coincide"
            fig.text(0.01, 0.005, note, fontsize=6, color="0.4")
        if not _numeric(values):
            ax.set_xticks(range(len(values)), [_short(str(v)) for v in values])
        ax.set_xlabel(with_unit(*labels[axis]))
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
        name = safe_name(axis.split(",")[0])
        paths.append(save_figure(fig, out / f"whatif_{outcome}_vs_{name}.png"))
    return paths


def _marks(
    ax: Axes, outcome: str, xs: np.ndarray, ys: np.ndarray, members: list, colour: str
) -> None:
    """A task held to the end of the run (a lower bound) as an upward triangle, a flagged
    case crossed out in red."""
    held = outcome == "task_held_s"
    bound = np.array([held and bool(r.get("task_held_is_lower_bound")) for r in members])
    if bound.any():
        ax.plot(xs[bound], ys[bound], "^", ms=10, mfc="none", color=colour)
    flagged = np.array([r["status"] == "flagged" for r in members])
    if flagged.any():
        ax.plot(xs[flagged], ys[flagged], "x", ms=11, mew=2, color="tab:red")


def _limits(ax: Axes, outcome: str) -> None:
    """What an answer is judged against: its limits dotted (the share capable on 0-100 %,
    the compression from 0 to above the design limit), the action levels of a score shaded
    and named by their level."""
    if outcome == "capable_pct":
        ax.set_ylim(0.0, 102.0)
    given = LIMITS.get(outcome, {})
    if given and outcome != "capable_pct":
        ax.set_ylim(0.0, 1.1 * max(ax.get_ylim()[1], min(given.values())))
    for text, limit in given.items():
        if limit > ax.get_ylim()[1]:
            continue
        ax.axhline(limit, ls=":", lw=1.2, color="0.35")
        ax.annotate(
            text,
            (0.99, limit),
            xycoords=("axes fraction", "data"),
            xytext=(0, -9),
            textcoords="offset points",
            fontsize=7,
            color="0.35",
            ha="right",
        )
    sheet = SHEETS.get(outcome)
    if sheet is None:
        return
    spans = bands(sheet)
    for (low, high, name), colour in zip(spans, BAND_COLOURS, strict=False):
        ax.axhspan(low, high, color=colour, alpha=0.13, lw=0, zorder=0)
        ax.text(
            1.01,
            (low + high) / 2,
            name.split(":")[0].replace(", ", "\n"),
            fontsize=6,
            color="0.3",
            transform=ax.get_yaxis_transform(),
            ha="left",
            va="center",
        )
    ax.set_ylim(0.5, spans[-1][1])
    ax.set_yticks(range(1, int(spans[-1][1]) + 1))


def _given(label: tuple[str, str], value: Any) -> str:
    """An axis and its value in a legend: ``box right/left half mass = 2 kg``."""
    words, unit = label
    shown = f"{value:g}" if isinstance(value, float) else _short(str(value))
    return f"{words} = {shown}" + (f" {unit}" if unit else "")


#: The most characters a value shows on a figure (a title of thousands does not fit).
SHOWN_CHARACTERS = 30


def _short(text: str) -> str:
    """``text`` as a figure shows it: cut to ``SHOWN_CHARACTERS``, ending in … if cut."""
    return text if len(text) <= SHOWN_CHARACTERS else text[: SHOWN_CHARACTERS - 1] + "…"


def _in_group(row: dict[str, Any], others: Sequence[tuple[str, list[Any]]], group: tuple) -> bool:
    """Whether a case has the other axes' values ``group``."""
    return all(str(axis_value(row, a)) == str(v) for (a, _), v in zip(others, group, strict=True))


def _position(row: dict[str, Any], axis: str, values: Sequence[Any]) -> float:
    """Where a case sits on the x axis: its value, or the value's index for text values."""
    value = axis_value(row, axis)
    return float(value) if _numeric(values) else float(values.index(value))


def _number(value: Any) -> float:
    """A plotted outcome: None (unlimited, never) is not drawn."""
    return np.nan if value is None else float(value)


def _numeric(values: Sequence[Any]) -> bool:
    return all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
