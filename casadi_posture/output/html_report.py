"""report.html: one self-contained page per run that opens offline in a browser. The
mannequin in 3-D (turned and zoomed with the mouse; a planar arm in its plane), the centre
of mass, the support polygon, the loads and the task targets; the curves of the groups
that tire most, their load, the task residuals, the L5/S1 compression and RULA/REBA, with
the events; a time slider that moves the body and a cursor on the curves together; and
the summary in words on top.

The page carries plotly.js once, gzip-compressed (the browser inflates it), the posture at
up to :data:`MAX_FRAMES` moments (every event's among them) as each body frame's
placement, and numbers to :data:`DIGITS` significant digits, so that a 20-minute run of
the 29-DOF body stays near 2.5 MB."""

from __future__ import annotations

import base64
import gzip
import html
import json
import math
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import plotly
import plotly.graph_objects as go
from matplotlib.colors import to_hex
from plotly.offline import get_plotlyjs
from plotly.subplots import make_subplots

from casadi_posture.biomech.low_back import limits as back_limits
from casadi_posture.output.key_postures import title
from casadi_posture.output.low_back import run_lines as back_lines
from casadi_posture.output.low_back import step_low_back
from casadi_posture.output.mannequin import CONTEXT, fill
from casadi_posture.output.outcome import outcome_lines
from casadi_posture.output.results import summary
from casadi_posture.output.scene import EDGE, SUPPORT, Scene, clip_line, plane_polygon
from casadi_posture.output.scores import run_lines as score_lines
from casadi_posture.output.scores import step_scores
from casadi_posture.output.scores import timeline_columns as score_columns
from casadi_posture.simulation import SimulationResult

#: Most moments the slider shows (every event's moment is added to them), most points of
#: a curve, most muscle groups drawn, significant digits of the numbers in the page.
MAX_FRAMES, MAX_POINTS, MAX_GROUPS, DIGITS = 300, 2000, 8, 4

#: The body's colour (its task limbs a deeper shade), and the groups' colours in turn.
BODY_COLOUR = "#1f77b4"
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

#: Height [m] above the floor of what is drawn on it (the support polygon, the centre of
#: mass's projection): on the floor itself, the floor would hide it.
LIFT = 0.003


def rounded(values: Any, digits: int = DIGITS) -> Any:
    """Numbers (nested lists or arrays) to ``digits`` significant digits; NaN as None."""
    array = np.asarray(values, dtype=float)
    flat = [None if not math.isfinite(v) else float(f"{v:.{digits}g}") for v in array.ravel()]
    return np.array(flat, dtype=object).reshape(array.shape).tolist()


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


def placements(result: SimulationResult, frames: list[str | None], steps: np.ndarray):
    """Each frame's placement at ``steps``: steps × frames × 3 × 4 (translation [m], then
    rotation: world = t + R·x0 for a point x0 of the frame at the zero posture)."""
    body = result.problem.body
    rows = [ca.horzcat(body.point(f, (0.0, 0.0, 0.0)), body.rotation(f)) for f in frames]
    function = ca.Function("placements", [body.q], [ca.vertcat(*rows)])
    q = result.timeline.q[steps]
    placed = np.asarray(function.map(len(q))(q.T))  # 3·frames × 4·steps
    return placed.reshape(len(frames), 3, len(q), 4).transpose(2, 0, 1, 3)


def _mesh_traces(scene: Scene, steps: np.ndarray) -> tuple[list[go.Mesh3d], list[dict], list]:
    """The mannequin as three surfaces (context parts, the rest, the task limbs), their
    parts' zero-posture points and frames for the page's script, and the frames'
    placements at ``steps``."""
    parts = scene.skeleton.parts
    frames = list(dict.fromkeys(part.dof for part in parts))
    kinds = {
        "context": [p for p in parts if p.context],
        "body": [p for p in parts if not p.context and p.limb not in scene.task_limbs],
        "task limbs": [p for p in parts if not p.context and p.limb in scene.task_limbs],
    }
    colours = {
        "context": CONTEXT[0],
        "body": fill(BODY_COLOUR, False, True),
        "task limbs": fill(BODY_COLOUR, True, True),
    }
    traces, meshes = [], []
    for name, members in kinds.items():
        if not members:
            continue
        zero, ijk, spans, start = [], [], [], 0
        for part in members:
            points = part.points()  # rings × n × 3
            rings, n = points.shape[:2]
            ring, column = np.meshgrid(np.arange(rings - 1), np.arange(n), indexing="ij")
            a = start + ring * n + column
            b = start + ring * n + (column + 1) % n
            c, d = a + n, b + n
            ijk += [np.c_[a.ravel(), b.ravel(), d.ravel()], np.c_[a.ravel(), d.ravel(), c.ravel()]]
            zero.append(points.reshape(-1, 3))
            spans.append([frames.index(part.dof), start, rings * n])
            start += rings * n
        i, j, k = np.vstack(ijk).T.tolist()
        traces.append(
            go.Mesh3d(
                x=[], y=[], z=[], i=i, j=j, k=k, name=name, color=to_hex(colours[name][:3]),
                flatshading=False, hoverinfo="name", showlegend=False,
                lighting={"ambient": 0.55, "diffuse": 0.7, "specular": 0.15, "roughness": 0.6},
            )
        )  # fmt: skip
        meshes.append({"zero": rounded(np.vstack(zero).ravel()), "parts": spans})
    return traces, meshes, rounded(placements(scene.result, frames, steps).reshape(len(steps), -1))


def _points(points: np.ndarray) -> dict[str, list]:
    """Per-step point lists (steps × points × axes) as the x, y (and z) of a trace."""
    return {axis: rounded(points[..., a]) for a, axis in enumerate("xyz"[: points.shape[-1]])}


def _body_figure(scene: Scene, steps: np.ndarray) -> tuple[go.Figure, dict[str, Any]]:
    """The body's view: in 3-D, or in the plane of a planar body; and the data that moves
    it to each of ``steps`` (traces by index)."""
    skeleton, result = scene.skeleton, scene.result
    three = not result.problem.body.planar
    axes = [0, 1, 2] if three else list(skeleton.plane)
    names = ("x forward (m)", "y left (m)", "z up (m)")
    Trace = go.Scatter3d if three else go.Scatter

    def trace(name: str, **style: Any) -> Any:
        return Trace(**{"xyz"[a]: [] for a in range(len(axes))}, name=name, **style)

    fig, moving = go.Figure(), []
    lo, hi = scene.lo, scene.hi
    if three and scene.floor:
        fig.add_trace(
            go.Mesh3d(
                x=[lo[0], hi[0], hi[0], lo[0]], y=[lo[1], lo[1], hi[1], hi[1]], z=[0.0] * 4,
                i=[0, 0], j=[1, 2], k=[2, 3], color="#ececec", name="floor", hoverinfo="skip",
                showlegend=False, lighting={"ambient": 1.0, "diffuse": 0.0},
            )
        )  # fmt: skip
    for shape in scene.shapes:
        fig.add_traces(_shape_traces(shape, scene, axes))
    meshes, placed = [], []
    if skeleton.parts and three:
        traces, meshes, placed = _mesh_traces(scene, steps)
        first = len(fig.data)
        fig.add_traces(traces)
        for k, mesh in enumerate(meshes):
            mesh["trace"] = first + k
    else:
        bones = np.stack([skeleton.segments(s)[:, axes] for s in steps])
        joints = np.stack([skeleton.points[s][axes][:, skeleton.joints].T for s in steps])
        moving += [
            (trace("body", mode="lines", line={"color": BODY_COLOUR, "width": 8}), _points(bones)),
            (
                trace("joints", mode="markers", marker={"color": BODY_COLOUR, "size": 6}),
                _points(joints),
            ),
        ]
    if scene.polygons and any(p is not None for p in scene.polygons.values()) and three:
        rings = [_closed(scene.polygons[s]) for s in steps]
        size = max(len(r) for r in rings)
        padded = np.stack([np.vstack([r, np.repeat(r[-1:], size - len(r), axis=0)]) for r in rings])
        support = trace(
            "support polygon (feet)", mode="lines", line={"color": EDGE, "width": 4},
            surfaceaxis=2, surfacecolor=SUPPORT,
        )  # fmt: skip
        moving.append((support, _points(padded)))
    com = skeleton.com[steps][:, axes]
    marker = {"size": 7 if three else 10, "color": "white", "line": {"color": "black", "width": 3}}
    moving.append((trace("centre of mass", mode="markers", marker=marker), _points(com[:, None])))
    if scene.floor and three:
        floor = skeleton.com[steps] * [1.0, 1.0, 0.0] + [0.0, 0.0, LIFT]
        drop = np.stack([skeleton.com[steps], floor], axis=1)
        line = {"color": "black", "width": 2, "dash": "dot"}
        moving.append(
            (trace("centre of mass over the floor", mode="lines", line=line), _points(drop))
        )
    for at, force, load in scene.loads:
        start = np.stack([skeleton.landmark(at, s) for s in steps])
        end = start + scene.arrow * force / np.linalg.norm(force)
        what = f"{load.mass:g} kg" if load.mass > 0 else f"{np.linalg.norm(force):.0f} N"
        arrow = np.stack([start, end], axis=1)[..., axes]
        style = {"color": "#444444", "width": 6} if three else {"color": "#444444", "width": 3}
        marker = {"symbol": "diamond" if three else "triangle-down", "size": 5 if three else 10}
        line = trace(f"load {load.name}: {what} at {at}", mode="lines+markers", line=style)
        line.marker = {**marker, "color": "#444444"}
        moving.append((line, _points(arrow)))
    first = len(fig.data)
    fig.add_traces([t for t, _ in moving])
    data = {
        "three": three,
        "meshes": meshes,
        "placements": placed,
        "moving": [{"trace": first + k, **points} for k, (_, points) in enumerate(moving)],
    }
    spans = hi - lo
    legend = {"orientation": "h", "x": 0.0, "y": 0.0, "yanchor": "top", "font": {"size": 11}}
    layout: dict[str, Any] = {"margin": {"l": 0, "r": 0, "t": 10, "b": 10}, "legend": legend}
    if three:
        scale = spans / spans.max()
        layout["scene"] = {
            **{
                f"{'xyz'[a]}axis": {"title": {"text": names[a]}, "range": [lo[a], hi[a]]}
                for a in range(3)
            },
            "aspectmode": "manual",
            "aspectratio": dict(zip("xyz", scale.tolist(), strict=True)),
            "camera": {"eye": {"x": 0.95, "y": -1.35, "z": 0.3}, "up": {"x": 0, "y": 0, "z": 1}},
        }
    else:
        i, j = axes
        layout["xaxis"] = {"title": {"text": names[i]}, "range": [lo[i], hi[i]]}
        layout["yaxis"] = {
            "title": {"text": names[j]}, "range": [lo[j], hi[j]], "scaleanchor": "x",
        }  # fmt: skip
        layout["margin"] = {"l": 60, "r": 10, "t": 10, "b": 40}
        legend["y"] = -0.1  # below the x axis' title
    fig.update_layout(**layout)
    return fig, data


def _closed(polygon: np.ndarray | None) -> np.ndarray:
    """A support polygon on the floor, closed (k+1 × 3 [m]); one NaN point when none."""
    if polygon is None or len(polygon) < 3:
        return np.full((1, 3), np.nan)
    ring = np.vstack([polygon, polygon[:1]])
    return np.c_[ring, np.full(len(ring), LIFT)]


def _shape_traces(shape: Any, scene: Scene, axes: list[int]) -> list[Any]:
    """A task's target: a point as a cross, a line dashed, a plane translucent (in 3-D)."""
    three = len(axes) == 3
    name = f"target: {shape.name}" if shape.kind == "point" else f"task {shape.kind}: {shape.name}"
    style = {"color": "#555555"}
    if shape.kind == "point":
        coords = {"xyz"[n]: [float(shape.point[a])] for n, a in enumerate(axes)}
        marker = {"symbol": "x", "size": 5 if three else 12, **style}
        kind = go.Scatter3d if three else go.Scatter
        return [kind(**coords, mode="markers", marker=marker, name=name)]
    if shape.kind == "line":
        ends = clip_line(shape.point, shape.vector, scene.lo, scene.hi)
        if ends is None:
            return []
        coords = {"xyz"[n]: ends[:, a].tolist() for n, a in enumerate(axes)}
        kind = go.Scatter3d if three else go.Scatter
        return [kind(**coords, mode="lines", line={**style, "dash": "dash"}, name=name)]
    corners = plane_polygon(shape.point, shape.vector, scene.lo, scene.hi)
    if corners is None or not three:
        return []
    fan = np.arange(1, len(corners) - 1)
    return [
        go.Mesh3d(
            x=corners[:, 0], y=corners[:, 1], z=corners[:, 2], i=[0] * len(fan), j=fan, k=fan + 1,
            color="#888888", opacity=0.15, name=name, showlegend=True, hoverinfo="name",
        )
    ]  # fmt: skip


def _curves_figure(
    result: SimulationResult, steps: np.ndarray, scale: float, unit: str
) -> tuple[go.Figure, list[str]]:
    """The curves against time [``unit``; ``scale`` s per unit] at ``steps``, one row
    each, and the rows' x axes (for the page's cursor)."""
    tl, body = result.timeline, result.problem.body
    halves = [h.name for h in body.half_joints]
    groups = shown_groups(result)
    back = step_low_back(result)
    scores = score_columns(result, step_scores(result))
    rows = ["fatigue (0-1)", "load (%MVC)", "task residuals"]
    rows += ["L5/S1 compression (N)"] if back is not None else []
    rows += ["RULA / REBA score"] if scores else []
    rows.append("events")
    heights = [1.0] * (len(rows) - 1) + [0.6]
    fig = make_subplots(
        rows=len(rows), cols=1, shared_xaxes=True, vertical_spacing=0.035,
        row_heights=heights, subplot_titles=rows,
    )  # fmt: skip
    t = rounded(tl.time[steps] / scale, 6)
    for n, k in enumerate(groups):
        colour = PALETTE[n % len(PALETTE)]
        style = {"x": t, "mode": "lines", "line": {"color": colour, "width": 1.6}}
        group = {"legendgroup": halves[k], "name": halves[k]}
        fig.add_trace(go.Scatter(y=rounded(tl.fatigue[steps, k]), **style, **group), 1, 1)
        fig.add_trace(
            go.Scatter(y=rounded(tl.load[steps, k]), **style, **group, showlegend=False), 2, 1
        )
    for level, value in (("fatigue threshold", result.settings.fatigue_threshold),
                         ("recovery threshold", result.settings.recovery_threshold)):  # fmt: skip
        fig.add_hline(y=value, line={"dash": "dot", "color": "#999999", "width": 1}, row=1, col=1)
        fig.add_annotation(
            text=level, x=1, xref="x domain", y=value, yref="y", showarrow=False,
            xanchor="right", yanchor="bottom", font={"size": 9, "color": "#777777"},
        )  # fmt: skip
    floor = 1e-6
    for k, (name, unit_k) in enumerate(zip(result.level_names, result.level_units, strict=True)):
        values = np.where(np.isnan(tl.residuals[steps, k]), np.nan, tl.residuals[steps, k])
        fig.add_trace(
            go.Scatter(
                x=t, y=rounded(np.maximum(values, floor)), mode="lines", legend="legend2",
                name=f"level {k + 1}: {name} ({unit_k})", line={"width": 1.4},
            ),
            3, 1,
        )  # fmt: skip
    fig.update_yaxes(type="log", row=3, col=1, exponentformat="power")
    row = 4
    if back is not None:
        fig.add_trace(
            go.Scatter(x=t, y=rounded(back.compression[steps]), mode="lines", legend="legend3",
                       name="compression", line={"color": "#8c564b"}),
            row, 1,
        )  # fmt: skip
        design = back_limits()["design"]
        fig.add_hline(y=design, line={"dash": "dash", "color": "#d62728", "width": 1}, row=row)
        fig.add_annotation(
            text=f"NIOSH design limit {design:g} N", x=1, xref="x domain", y=design,
            yref=f"y{row}", showarrow=False, xanchor="right", yanchor="bottom",
            font={"size": 9, "color": "#d62728"},
        )  # fmt: skip
        peak = float(np.nanmax(back.compression)) if np.isfinite(back.compression).any() else 0.0
        fig.update_yaxes(range=[0, 1.1 * max(peak, design)], row=row, col=1)
        row += 1
    if scores:
        for name, values in scores.items():
            shown = np.array([np.nan if v is None else v for v in values], dtype=float)[steps]
            fig.add_trace(
                go.Scatter(x=t, y=rounded(shown), mode="lines", legend="legend4",
                           name=name.replace("_", " ").upper().replace(" R", " right")
                           .replace(" L", " left"), line={"shape": "hv", "width": 1.4}),
                row, 1,
            )  # fmt: skip
        fig.update_yaxes(range=[0, 15], row=row, col=1)
        row += 1
    _events(fig, result, groups, scale, row)
    fig.update_xaxes(title={"text": f"time ({unit})"}, row=row, col=1)
    fig.update_yaxes(range=[0, 1.05], row=1, col=1)
    fig.update_xaxes(showspikes=False)
    legends = {"legend": 1, "legend2": 3, "legend3": 4, "legend4": 4 + (back is not None)}
    layout: dict[str, Any] = {
        "margin": {"l": 60, "r": 10, "t": 30, "b": 40},
        "hovermode": "x",
        "template": "plotly_white",
        "font": {"size": 11},
    }
    for name, at in legends.items():
        domain = fig.layout[f"yaxis{at if at > 1 else ''}"].domain
        layout[name] = {"x": 1.01, "y": domain[1], "yanchor": "top", "font": {"size": 10}}
    layout["legend5"] = {"x": 1.01, "y": fig.layout[f"yaxis{row}"].domain[1], "yanchor": "top",
                         "font": {"size": 10}}  # fmt: skip
    fig.update_layout(**layout)
    for annotation in fig.layout.annotations[: len(rows)]:
        annotation.update(x=0, xanchor="left", font={"size": 12})
    return fig, [f"x{r if r > 1 else ''}" for r in range(1, row + 1)]


def _events(fig: go.Figure, result: SimulationResult, groups: list[int], scale: float, row: int):
    """The events: on their group's fatigue curve (when drawn) and, all of them, in a strip
    of their own, one line per kind; the hover says what happened."""
    tl, halves = result.timeline, [h.name for h in result.problem.body.half_joints]
    kinds = list(dict.fromkeys(e.kind for e in result.events))
    for kind in kinds:
        chosen = [e for e in result.events if e.kind == kind]
        symbol, colour = MARKS.get(kind, ("circle", "#333333"))
        text = [f"{e.time_s:g} s: {e.kind} {e.half_joint} {e.detail}".strip() for e in chosen]
        times = rounded([e.time_s / scale for e in chosen], 6)
        marker = {"symbol": symbol, "color": colour, "size": 9, "line": {"width": 1}}
        fig.add_trace(
            go.Scatter(x=times, y=[kind.replace("_", " ")] * len(chosen), mode="markers",
                       marker=marker, text=text, hoverinfo="text", name=kind.replace("_", " "),
                       legend="legend5", legendgroup=f"event {kind}"),
            row, 1,
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
        fig.add_trace(
            go.Scatter(
                x=rounded([e.time_s / scale for e in on_curves], 6), y=rounded(at),
                mode="markers", marker=marker, hoverinfo="text", showlegend=False,
                text=[f"{e.time_s:g} s: {e.kind} {e.half_joint} {e.detail}" for e in on_curves],
                legendgroup=f"event {kind}",
            ),
            1, 1,
        )  # fmt: skip
    fig.update_yaxes(type="category", row=row, col=1, categoryarray=[k.replace("_", " ")
                                                                      for k in kinds])  # fmt: skip


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


def _when(seconds: float) -> tuple[float, str]:
    """The curves' time unit for a run of ``seconds``: s per unit and its name."""
    return (60.0, "min") if seconds > 300 else (1.0, "s")


@cache
def _plotly_gzip() -> str:
    """plotly.js, gzip-compressed and base64-encoded (about 1.9 MB instead of 4.8)."""
    return base64.b64encode(gzip.compress(get_plotlyjs().encode(), 9, mtime=0)).decode()


def report_html(result: SimulationResult) -> str:
    """The page of a run that ran at least one step."""
    tl = result.timeline
    report = summary(result)
    scale, unit = _when(float(tl.time[-1]))
    frames = frame_steps(tl.time, [e.time_s for e in result.events])
    scene = Scene(result, frames.tolist())
    body, moves = _body_figure(scene, frames)
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
    heading = html.escape(result.problem.spec.title or title(result))
    overrides = result.problem.overrides
    changed = f" with {', '.join(f'{k} = {v}' for k, v in overrides.items())}" if overrides else ""
    script = resources.files("casadi_posture.output").joinpath("html_report.js").read_text()
    return PAGE.format(
        title=heading,
        subtitle=html.escape(
            f"{result.problem.path}{changed} · {title(result)} · plotly {plotly.__version__}"
        ),
        summary=summary_html(report),
        plotly=_plotly_gzip(),
        body=_inline(body.to_json()),
        curves=_inline(curves.to_json()),
        data=_inline(json.dumps(data, separators=(",", ":"))),
        frames=len(frames) - 1,
        script=script,
    )


def _inline(text: str) -> str:
    """JSON safe inside a <script> element."""
    return text.replace("</", "<\\/")


def write_report(result: SimulationResult, path: Path) -> Path | None:
    """report.html of a run into ``path`` (written whole or not at all); None when no step
    was run."""
    if result.timeline.time.size == 0:
        return None
    partial = path.with_name(path.name + ".partial")
    try:
        partial.write_text(report_html(result), encoding="utf-8")
        partial.replace(path)
    finally:
        partial.unlink(missing_ok=True)
    return path


PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 0 1em; color: #222; }}
h1 {{ font-size: 1.3em; margin: 0.5em 0 0; }} .sub {{ color: #666; font-size: 0.85em; }}
#summary ul {{ margin: 0.3em 0; padding-left: 1.2em; }} .flags {{ color: #b00020; }}
.ok {{ color: #2a7a2a; margin: 0.2em 0; }}
#views {{ display: flex; flex-wrap: wrap; gap: 0.5em; }}
#body {{ flex: 1 1 480px; height: 760px; min-width: 360px; }}
#curves {{ flex: 1.4 1 620px; height: 900px; min-width: 480px; }}
#controls {{ display: flex; align-items: center; gap: 0.8em; margin: 0.4em 0;
  position: sticky; top: 0; background: white; z-index: 5; padding: 0.3em 0; }}
#slider {{ flex: 1; }} #clock {{ min-width: 22em; font-variant-numeric: tabular-nums; }}
#loading {{ color: #666; }}
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
