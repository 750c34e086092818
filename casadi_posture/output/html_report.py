"""report.html: one self-contained page per run that opens offline in a browser. The
mannequin in 3-D (turned and zoomed with the mouse; a planar arm in its plane), the centre
of mass, the support polygon, the loads and the task targets; the curves of the groups
that tire most, their load, the task residuals, the L5/S1 compression and RULA/REBA, with
the events; a time slider that moves the body and a cursor on the curves together; and
the summary in words on top.

The page carries plotly.js once, gzip-compressed (the browser inflates it), the posture at
up to ``MAX_FRAMES`` moments (every event's among them) as each body frame's
placement, and numbers to ``DIGITS`` significant digits, so that a 20-minute run of
the 29-DOF body stays near 2.5 MB."""

from __future__ import annotations

import html
from pathlib import Path
from typing import Any

import numpy as np

from casadi_posture.biomech.low_back import limits as back_limits
from casadi_posture.output.html_body import body_figure
from casadi_posture.output.html_page import (
    HEAD,
    plotly_gzip,
    problem_line,
    script_json,
    scripts,
    write_page,
)
from casadi_posture.output.key_postures import title
from casadi_posture.output.low_back import run_lines as back_lines
from casadi_posture.output.low_back import step_low_back
from casadi_posture.output.outcome import outcome_lines
from casadi_posture.output.plotly_json import (
    axis_name,
    hline,
    rounded,
    stacked_rows,
    template,
    version,
)
from casadi_posture.output.results import summary
from casadi_posture.output.scene import Scene
from casadi_posture.output.scores import run_lines as score_lines
from casadi_posture.output.scores import step_scores
from casadi_posture.output.scores import timeline_columns as score_columns
from casadi_posture.output.time_axis import time_unit
from casadi_posture.simulation import SimulationResult

#: Most moments the slider shows (every event's moment is added to them), most points of
#: a curve, most muscle groups drawn.
MAX_FRAMES, MAX_POINTS, MAX_GROUPS = 300, 2000, 8

#: The groups' colours in turn.
PALETTE = ("#d62728", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f")

#: How each kind of event is marked: symbol and colour.
MARKS = {
    "fatigue_threshold": ("triangle-up", "#d62728"),
    "recovery_threshold": ("triangle-down", "#2ca02c"),
    "constraint_on": ("square", "#ff7f0e"),
    "constraint_off": ("square-open", "#ff7f0e"),
    "constraint_blocked": ("x", "#8c564b"),
    "exhausted": ("star", "#000000"),
    "over_strength": ("diamond", "#000000"),
    "task_not_held": ("circle-open", "#9467bd"),
    "solver_fallback": ("cross", "#7f7f7f"),
    "interrupted": ("hourglass", "#000000"),
}


def frame_steps(time: np.ndarray, event_times: list[float], limit: int = MAX_FRAMES) -> np.ndarray:
    """The steps the slider shows: ``limit`` evenly spread from the first to the last, and
    the first step at or after every event (all of them, whatever ``limit``)."""
    spread = np.linspace(0, time.size - 1, min(limit, time.size)).round().astype(int)
    events = np.searchsorted(time, np.asarray(event_times, dtype=float) - 1e-9)
    return np.unique(np.r_[spread, np.minimum(events, time.size - 1)])


def curve_steps(time: np.ndarray, frames: np.ndarray, limit: int = MAX_POINTS) -> np.ndarray:
    """The steps the curves go through: all of them, or ``limit`` evenly spread and the
    slider's."""
    if time.size <= limit:
        return np.arange(time.size)
    return np.unique(np.r_[np.linspace(0, time.size - 1, limit).round().astype(int), frames])


def shown_groups(result: SimulationResult, limit: int = MAX_GROUPS) -> list[int]:
    """The half-joints drawn: those that tire most, then those most loaded [%MVC]; none
    that carries nothing."""
    tl = result.timeline
    peak_fatigue, peak_load = tl.fatigue.max(axis=0), np.nan_to_num(tl.load).max(axis=0)
    order = np.lexsort((-peak_load, -peak_fatigue))
    return [int(k) for k in order if peak_fatigue[k] > 0 or peak_load[k] > 0][:limit]


def _curves_figure(
    result: SimulationResult, steps: np.ndarray, scale: float, unit: str
) -> tuple[dict[str, Any], list[str]]:
    """The curves against time [``unit``; ``scale`` s per unit] at ``steps``, one row
    each (a plotly figure's data), and the rows' x axes (for the page's cursor)."""
    tl, body = result.timeline, result.problem.body
    halves = [h.name for h in body.half_joints]
    groups = shown_groups(result)
    back = step_low_back(result)
    scores = score_columns(result, step_scores(result))
    fitted = _fit_residuals(result)
    third = "task residuals" if result.level_names or not fitted else fitted[0]
    rows = ["fatigue (0-1)", "load (%MVC)", third]
    rows += ["L5/S1 compression (N)"] if back is not None else []
    rows += ["RULA / REBA score"] if scores else []
    rows.append("events")
    layout, domains = stacked_rows(rows, [1.0] * (len(rows) - 1) + [0.6], spacing=0.035)
    data: list[dict[str, Any]] = []
    shapes: list[dict[str, Any]] = []

    def add(row: int, **trace: Any) -> None:
        data.append({"type": "scatter", **trace, "xaxis": axis_name("x", row),
                     "yaxis": axis_name("y", row)})  # fmt: skip

    def level(value: float, row: int, text: str, dash: str, colour: str, ink: str) -> None:
        """A labelled horizontal line: ``colour`` the line's, ``ink`` its label's."""
        shapes.append(hline(value, row, {"color": colour, "dash": dash, "width": 1}))
        layout["annotations"].append(
            {"text": text, "x": 1, "xref": f"{axis_name('x', row)} domain", "y": value,
             "yref": axis_name("y", row), "showarrow": False, "xanchor": "right",
             "yanchor": "bottom", "font": {"size": 9, "color": ink}}
        )  # fmt: skip

    t = rounded(tl.time[steps] / scale, 6)
    for n, k in enumerate(groups):
        line = {"color": PALETTE[n % len(PALETTE)], "width": 1.6}
        style = {"x": t, "mode": "lines", "line": line}
        group = {"legendgroup": halves[k], "name": halves[k]}
        add(1, y=rounded(tl.fatigue[steps, k]), **style, **group)
        add(2, y=rounded(tl.load[steps, k]), **style, **group, showlegend=False)
    for name, value in (("fatigue threshold", result.settings.fatigue_threshold),
                        ("recovery threshold", result.settings.recovery_threshold)):  # fmt: skip
        level(value, 1, name, "dot", "#999999", "#777777")
    floor = 1e-6
    for k, (name, unit_k) in enumerate(zip(result.level_names, result.level_units, strict=True)):
        add(3, x=t, y=rounded(np.maximum(tl.residuals[steps, k], floor)), mode="lines",
            legend="legend2", name=f"level {k + 1}: {name} ({unit_k})",
            line={"width": 1.4})  # fmt: skip
    if fitted and not result.level_names:
        for name, values in fitted[1].items():
            add(3, x=t, y=rounded(np.maximum(values[steps], floor)), mode="lines",
                legend="legend2", name=name, line={"width": 1.2})  # fmt: skip
    layout["yaxis3"] |= {"type": "log", "exponentformat": "power"}
    row = 4
    if back is not None:
        add(row, x=t, y=rounded(back.compression[steps]), mode="lines", legend="legend3",
            name="compression", line={"color": "#8c564b"})  # fmt: skip
        design = back_limits()["design"]
        level(design, row, f"NIOSH design limit {design:g} N", "dash", "#d62728", "#d62728")
        peak = float(np.nanmax(back.compression)) if np.isfinite(back.compression).any() else 0.0
        layout[f"yaxis{row}"]["range"] = [0, 1.1 * max(peak, design)]
        row += 1
    if scores:
        for name, values in scores.items():
            shown = np.array([np.nan if v is None else v for v in values], dtype=float)[steps]
            label = name.replace("_", " ").upper().replace(" R", " right").replace(" L", " left")
            add(row, x=t, y=rounded(shown), mode="lines", legend="legend4", name=label,
                line={"shape": "hv", "width": 1.4})  # fmt: skip
        layout[f"yaxis{row}"]["range"] = [0, 15]
        row += 1
    data += _events(result, groups, scale, row, layout)
    layout[f"xaxis{row}"]["title"] = {"text": f"time ({unit})"}
    for r in range(1, row + 1):
        layout[f"xaxis{r if r > 1 else ''}"]["showspikes"] = False
    layout["yaxis"]["range"] = [0, 1.05]
    legends = {"legend": 1, "legend2": 3, "legend3": 4, "legend4": 4 + (back is not None)}
    legends["legend5"] = row
    for name, at in legends.items():
        layout[name] = {"x": 1.01, "y": domains[at - 1][1], "yanchor": "top", "font": {"size": 10}}
    layout |= {
        "template": template("plotly_white"),
        "margin": {"l": 60, "r": 10, "t": 30, "b": 40},
        "hovermode": "x",
        "font": {"size": 11},
        "shapes": shapes,
    }
    return {"data": data, "layout": layout}, [axis_name("x", r) for r in range(1, row + 1)]


def _events(
    result: SimulationResult, groups: list[int], scale: float, row: int, layout: dict[str, Any]
) -> list[dict[str, Any]]:
    """The events' traces: on their group's fatigue curve (when drawn) and, all of them, in
    a strip of their own (row ``row``, a category axis set in ``layout``), one line per
    kind; the hover says what happened."""
    tl, halves = result.timeline, [h.name for h in result.problem.body.half_joints]
    kinds = list(dict.fromkeys(e.kind for e in result.events))
    strip = {"xaxis": axis_name("x", row), "yaxis": axis_name("y", row)}
    traces = []
    for kind in kinds:
        chosen = [e for e in result.events if e.kind == kind]
        symbol, colour = MARKS.get(kind, ("circle", "#333333"))
        text = [f"{e.time_s:g} s: {e.kind} {e.half_joint} {e.detail}".strip() for e in chosen]
        marker = {"symbol": symbol, "color": colour, "size": 9, "line": {"width": 1}}
        traces.append(
            {"type": "scatter", "x": rounded([e.time_s / scale for e in chosen], 6),
             "y": [kind.replace("_", " ")] * len(chosen), "mode": "markers", "marker": marker,
             "text": text, "hoverinfo": "text", "name": kind.replace("_", " "),
             "legend": "legend5", "legendgroup": f"event {kind}", **strip}
        )  # fmt: skip
        on_curves = [e for e in chosen if e.half_joint in halves and halves.index(e.half_joint)
                     in groups]  # fmt: skip
        if not on_curves:
            continue
        at = [
            float(tl.fatigue[min(np.searchsorted(tl.time, e.time_s), tl.time.size - 1),
                             halves.index(e.half_joint)])
            for e in on_curves
        ]  # fmt: skip
        traces.append(
            {"type": "scatter", "x": rounded([e.time_s / scale for e in on_curves], 6),
             "y": rounded(at), "mode": "markers", "marker": marker, "hoverinfo": "text",
             "showlegend": False, "legendgroup": f"event {kind}", "xaxis": "x", "yaxis": "y",
             "text": [f"{e.time_s:g} s: {e.kind} {e.half_joint} {e.detail}" for e in on_curves]}
        )  # fmt: skip
    layout[f"yaxis{row}"] |= {"type": "category", "categoryarray": [k.replace("_", " ")
                                                                     for k in kinds]}  # fmt: skip
    return traces


def summary_html(report: dict[str, Any]) -> str:
    """summary.json in words, as HTML: the console's outcome lines (what was held and how
    long, which group limits and which gave out), the scores and the low back, the balance
    margin, the flags."""
    lines = outcome_lines(report) + score_lines(report["rula_reba"])
    lines += back_lines(report["low_back"])
    if report["balance_margin_min_m"] is not None:
        lines.append(
            f"smallest balance margin: {100 * report['balance_margin_min_m']:.1f} cm (the "
            "centre of mass inside the support polygon when positive)"
        )
    items = "".join(f"<li>{html.escape(line.strip())}</li>" for line in lines)
    flags = "".join(f"<li>FLAGGED: {html.escape(f)}</li>" for f in report["flags"])
    verdict = (
        f"<ul class='flags'>{flags}</ul>"
        if flags
        else "<p class='ok'>No flags: the answer can be used as it is.</p>"
    )
    return f"<ul>{items}</ul>{verdict}"


#: Fitted points drawn in a recording's fit panel, the worst first (timeline.csv has all).
DRAWN_FIT_POINTS = 6


def _fit_residuals(result: SimulationResult) -> tuple[str, dict[str, np.ndarray]] | None:
    """A recording's IK fit per frame, for the panel a run's task residuals take: its title
    and each fitted point's residual (C3D: mm; BVH: deg), the ``DRAWN_FIT_POINTS`` with
    the largest; None for any other run."""
    recording = result.recording
    if recording is None or not recording.residuals:
        return None
    size = result.timeline.time.size
    unit, scale = recording.residual_unit
    what = "BVH joints"
    if unit == "m":  # markers, shown in mm
        what, unit, scale = "markers", "mm", 1e3 * scale
    values = {k: scale * v[:size] for k, v in recording.residuals.items()}
    if len(values) > DRAWN_FIT_POINTS:  # the worst, so that the legend fits its panel
        worst = sorted(values, key=lambda k: -float(np.max(values[k])))[:DRAWN_FIT_POINTS]
        title = f"fit to the {what} ({unit}), the {DRAWN_FIT_POINTS} worst of {len(values)}"
        return title, {k: values[k] for k in values if k in worst}
    return f"fit to the {what} ({unit})", values


def report_html(result: SimulationResult) -> str:
    """The page of a run that ran at least one step."""
    tl = result.timeline
    report = summary(result)
    scale, unit = time_unit(tl.time)
    frames = frame_steps(tl.time, [e.time_s for e in result.events])
    scene = Scene.of_run(result, frames.tolist())
    body, moves = body_figure(scene, frames)
    curves, cursor_axes = _curves_figure(result, curve_steps(tl.time, frames), scale, unit)
    halves = [h.name for h in result.problem.body.half_joints]
    owner = [halves[o] if o >= 0 else "" for o in tl.owner[frames]]
    data = {
        "time": rounded(tl.time[frames], 6),
        "scale": scale,
        "unit": unit,
        "phase": [tl.phase[s] for s in frames],
        "owner": owner,
        "cursor": cursor_axes,
        **moves,
    }
    heading = html.escape(result.problem.heading or title(result))
    return PAGE.format(
        title=heading,
        subtitle=html.escape(
            f"{problem_line(result.problem)} · {title(result)} · plotly {version()}"
        ),
        summary=summary_html(report),
        plotly=plotly_gzip(),
        body=script_json(body),
        curves=script_json(curves),
        data=script_json(data),
        frames=len(frames) - 1,
        script=scripts("viewer.js", "html_report.js"),
    )


def write_report(result: SimulationResult, path: Path) -> Path | None:
    """report.html of a run into ``path`` (written whole or not at all); None when no step
    was run."""
    if result.timeline.time.size == 0:
        return None
    return write_page(report_html(result), path)


PAGE = (
    HEAD
    + """
#body {{ flex: 1 1 480px; height: 760px; min-width: 360px; }}
#curves {{ flex: 1.4 1 620px; height: 900px; min-width: 480px; }}
#controls {{ display: flex; align-items: center; gap: 0.8em; margin: 0.4em 0;
  position: sticky; top: 0; background: white; z-index: 5; padding: 0.3em 0; }}
#slider {{ flex: 1; }} #clock {{ min-width: 22em; font-variant-numeric: tabular-nums; }}
</style></head><body>
<h1>{title}</h1><div class="sub">{subtitle}</div>
<div id="summary">{summary}</div>
<div id="controls"><button id="play" type="button">play</button>
<input id="slider" type="range" min="0" max="{frames}" value="0" step="1"
 aria-label="time"><span id="clock"></span></div>
<p id="loading">Loading the plots (this page needs a browser from 2023 or later)...</p>
<div id="views"><div id="body"></div><div id="curves"></div></div>
<script id="plotly-gz" type="application/octet-stream">{plotly}</script>
<script id="body-figure" type="application/json">{body}</script>
<script id="curves-figure" type="application/json">{curves}</script>
<script id="report-data" type="application/json">{data}</script>
<script>
{script}
</script>
</body></html>
"""
)
