"""The body's view in an HTML page: the mannequin in 3-D (turned and zoomed with the mouse;
a planar body in its plane) with the floor, the support polygon, the centre of mass, the
loads and the tasks' targets, as a plotly figure; and, per posture shown, what the page's
script needs to move it there (each body frame's placement, the moving traces' points)."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from matplotlib.colors import to_hex

from casadi_posture.body.tree import BodyModel
from casadi_posture.output.mannequin import CONTEXT, fill
from casadi_posture.output.plotly_json import rounded, template
from casadi_posture.output.scene import EDGE, SUPPORT, Scene, clip_line, plane_polygon

#: The body's colour (its task limbs a deeper shade).
BODY_COLOUR = "#1f77b4"

#: Height [m] above the floor of what is drawn on it (the support polygon, the centre of
#: mass's projection): on the floor itself, the floor would hide it.
LIFT = 0.003


def placements(body: BodyModel, q: np.ndarray, frames: list[str | None], steps: np.ndarray):
    """Each frame's placement at the rows ``steps`` of ``q`` [rad]: steps × frames × 3 × 4
    (translation [m], then rotation: world = t + R·x0 for a point x0 of the frame at the
    zero posture)."""
    rows = [ca.horzcat(body.point(f, (0.0, 0.0, 0.0)), body.rotation(f)) for f in frames]
    function = ca.Function("placements", [body.q], [ca.vertcat(*rows)])
    q = q[steps]
    placed = np.asarray(function.map(len(q))(q.T))  # 3·frames × 4·steps
    return placed.reshape(len(frames), 3, len(q), 4).transpose(2, 0, 1, 3)


def _mesh_traces(scene: Scene, steps: np.ndarray) -> tuple[list[dict], list[dict], list]:
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
            {
                "type": "mesh3d", "x": [], "y": [], "z": [], "i": i, "j": j, "k": k, "name": name,
                "color": to_hex(colours[name][:3]), "flatshading": False, "hoverinfo": "name",
                "showlegend": False,
                "lighting": {"ambient": 0.55, "diffuse": 0.7, "specular": 0.15, "roughness": 0.6},
            }
        )  # fmt: skip
        meshes.append({"zero": rounded(np.vstack(zero).ravel()), "parts": spans})
    return (
        traces,
        meshes,
        rounded(placements(scene.problem.body, scene.q, frames, steps).reshape(len(steps), -1)),
    )


def _points(points: np.ndarray) -> dict[str, list]:
    """Per-step point lists (steps × points × axes) as the x, y (and z) of a trace."""
    return {axis: rounded(points[..., a]) for a, axis in enumerate("xyz"[: points.shape[-1]])}


def body_figure(scene: Scene, steps: np.ndarray) -> tuple[dict[str, Any], dict[str, Any]]:
    """The body's view (a plotly figure's data): in 3-D, or in the plane of a planar body;
    and the data that moves it to each of ``steps`` (traces by index)."""
    skeleton = scene.skeleton
    three = not scene.problem.body.planar
    axes = [0, 1, 2] if three else list(skeleton.plane)
    names = ("x forward (m)", "y left (m)", "z up (m)")
    kind = "scatter3d" if three else "scatter"

    def trace(name: str, **style: Any) -> dict[str, Any]:
        return {"type": kind, **{"xyz"[a]: [] for a in range(len(axes))}, "name": name, **style}

    data: list[dict[str, Any]] = []
    moving: list[tuple[dict[str, Any], dict[str, list]]] = []
    lo, hi = scene.lo, scene.hi
    if three and scene.floor:
        data.append(
            {
                "type": "mesh3d", "x": [lo[0], hi[0], hi[0], lo[0]],
                "y": [lo[1], lo[1], hi[1], hi[1]], "z": [0.0] * 4, "i": [0, 0], "j": [1, 2],
                "k": [2, 3], "color": "#ececec",
                "name": "floor", "hoverinfo": "skip", "showlegend": False,
                "lighting": {"ambient": 1.0, "diffuse": 0.0},
            }
        )  # fmt: skip
    for shape in scene.shapes:
        data += _shape_traces(shape, scene, axes)
    meshes, placed = [], []
    if skeleton.parts and three:
        traces, meshes, placed = _mesh_traces(scene, steps)
        first = len(data)
        data += traces
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
        line = trace(
            f"load {load.name}: {what} at {at}", mode="lines+markers", line=style,
            marker={**marker, "color": "#444444"},
        )  # fmt: skip
        moving.append((line, _points(arrow)))
    first = len(data)
    data += [t for t, _ in moving]
    moves = {
        "three": three,
        "meshes": meshes,
        "placements": placed,
        "moving": [{"trace": first + k, **points} for k, (_, points) in enumerate(moving)],
    }
    spans = hi - lo
    legend = {"orientation": "h", "x": 0.0, "y": 0.0, "yanchor": "top", "font": {"size": 11}}
    layout: dict[str, Any] = {
        "template": template("plotly"),
        "margin": {"l": 0, "r": 0, "t": 10, "b": 10},
        "legend": legend,
    }
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
    return {"data": data, "layout": layout}, moves


def _closed(polygon: np.ndarray | None) -> np.ndarray:
    """A support polygon on the floor, closed (k+1 × 3 [m]); one NaN point when none."""
    if polygon is None or len(polygon) < 3:
        return np.full((1, 3), np.nan)
    ring = np.vstack([polygon, polygon[:1]])
    return np.c_[ring, np.full(len(ring), LIFT)]


def _shape_traces(shape: Any, scene: Scene, axes: list[int]) -> list[dict[str, Any]]:
    """A task's target: a point as a cross, a line dashed, a plane translucent (in 3-D)."""
    three = len(axes) == 3
    name = f"target: {shape.name}" if shape.kind == "point" else f"task {shape.kind}: {shape.name}"
    style = {"color": "#555555"}
    kind = "scatter3d" if three else "scatter"
    if shape.kind == "point":
        coords = {"xyz"[n]: [float(shape.point[a])] for n, a in enumerate(axes)}
        marker = {"symbol": "x", "size": 5 if three else 12, **style}
        return [{"type": kind, **coords, "mode": "markers", "marker": marker, "name": name}]
    if shape.kind == "line":
        ends = clip_line(shape.point, shape.vector, scene.lo, scene.hi)
        if ends is None:
            return []
        coords = {"xyz"[n]: ends[:, a].tolist() for n, a in enumerate(axes)}
        line = {**style, "dash": "dash"}
        return [{"type": kind, **coords, "mode": "lines", "line": line, "name": name}]
    corners = plane_polygon(shape.point, shape.vector, scene.lo, scene.hi)
    if corners is None or not three:
        return []
    fan = np.arange(1, len(corners) - 1)
    return [
        {
            "type": "mesh3d", "x": corners[:, 0].tolist(), "y": corners[:, 1].tolist(),
            "z": corners[:, 2].tolist(), "i": [0] * len(fan), "j": fan.tolist(),
            "k": (fan + 1).tolist(), "color": "#888888", "opacity": 0.15, "name": name,
            "showlegend": True, "hoverinfo": "name",
        }
    ]  # fmt: skip
