"""report.html of a posture, not a run: ``solve``'s (the posture the IK found, beside the
start it was solved from) and, with runs/compare_report.py, ``compare``'s (per problem the
start and both solvers' postures). One self-contained page that opens offline: the body's
view of html_body.py with a button per posture, the summary in words and the flags, the
loads, and the tables; with several cases, a table whose row picks the case shown."""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from casadi_posture.output import low_back
from casadi_posture.output.html_body import body_figure
from casadi_posture.output.html_page import (
    HEAD,
    plotly_gzip,
    problem_line,
    script_json,
    scripts,
    table,
    write_page,
)
from casadi_posture.output.plotly_json import template, version
from casadi_posture.output.report import HALF_JOINT_COLUMNS
from casadi_posture.output.scene import Scene
from casadi_posture.output.scores import lines as score_lines
from casadi_posture.problem import Problem
from casadi_posture.static import StaticAnswer

#: Most loaded half-joints drawn in a solved posture's load chart.
LOADED = 10


@dataclass(frozen=True)
class Case:
    """One problem on a page: its ``name``, the ``postures`` drawn (label, q [rad]; the
    last is shown first), the ``lines`` of its summary, its ``flags``, its ``tables``
    (HTML) and a chart of its loads (or None)."""

    name: str
    problem: Problem
    postures: tuple[tuple[str, np.ndarray], ...]
    lines: tuple[str, ...]
    flags: tuple[str, ...]
    tables: str
    chart: dict[str, Any] | None = None


def solve_case(answer: StaticAnswer) -> Case:
    """The page's case of a solved posture: the start and the answer, the levels and
    what the answer loads."""
    problem, ik = answer.problem, answer.ik
    assert ik is not None, "a solved answer"
    lines = [
        f"{ik.solver} solver: {ik.status}, {ik.iterations} iterations, "
        f"{1e3 * ik.wall_time_s:.1f} ms"
    ]
    lines += [
        f"level {lv.level} ({lv.tasks}): residual {lv.residual:.3g} {lv.unit}, "
        + {"yes": "achieved", "NO": "NOT achieved"}.get(lv.outcome, lv.outcome)
        for lv in answer.levels
    ]
    group = answer.limiting
    if group is not None:
        lines.append(
            f"most tiring: {group.name} at {group.load_pct_mvc:.1f} %MVC, endurance "
            f"{minutes(group.endurance_min)}"
        )
    lines += [answer.capable.task_line()]
    lines += [f"plausibility of the {answer.plausibility.line()}"] if answer.plausibility else []
    lines += [line.strip() for line in score_lines(problem, answer.scores)]
    lines += [line.strip() for line in low_back.lines(answer.low_back)]
    start = np.asarray(problem.posture, dtype=float)
    dofs = [
        [d["name"], math.degrees(start[i]), d["angle_deg"], d["external_Nm"], d["passive_Nm"],
         d["active_Nm"]]
        for i, d in enumerate(answer.dofs())
    ]  # fmt: skip
    tables = section(
        "Priority levels",
        table(
            ["level", "tasks", "residual", "unit", "achieved"],
            [[lv.level, lv.tasks, lv.residual, lv.unit, lv.outcome] for lv in answer.levels],
        ),
    )
    loaded = sorted(answer.half_joints(), key=lambda g: -g["load_pct_mvc"])
    tables += section(
        "Half-joints",
        table(HALF_JOINT_COLUMNS, [list(g.values()) for g in loaded], **{"class": "sortable"}),
        closed=True,
    )
    tables += section(
        "DOFs",
        table(
            [
                "DOF",
                "start (deg)",
                "answer (deg)",
                "external (N·m)",
                "passive (N·m)",
                "active (N·m)",
            ],
            dofs,
            **{"class": "sortable"},
        ),
        closed=True,
    )
    return Case(
        name=str(problem.path),
        problem=problem,
        postures=(("start (posture_deg)", start), (f"answer ({ik.solver})", ik.q)),
        lines=tuple(lines),
        flags=tuple(answer.flags),
        tables=tables,
        chart=_loads_chart(answer),
    )


def minutes(value: float) -> str:
    return f"{value:.2f} min" if math.isfinite(value) else "unlimited"


def section(heading: str, content: str, *, closed: bool = False) -> str:
    """A titled block; ``closed``: folded until clicked."""
    if closed:
        return f"<details><summary>{html.escape(heading)}</summary>{content}</details>"
    return f"<h3>{html.escape(heading)}</h3>{content}"


def _loads_chart(answer: StaticAnswer) -> dict[str, Any]:
    """The most loaded half-joints' load [%MVC] at the answer (none that carries nothing),
    the strength (100 %MVC) drawn; the hover gives torque, strength and endurance."""
    loaded = [g for g in answer.groups if g.load_pct_mvc > 0]
    groups = sorted(loaded, key=lambda g: -g.load_pct_mvc)[:LOADED][::-1]
    hover = [
        f"{g.name}: {g.torque:.1f} of {g.strength:.1f} N·m, endurance {minutes(g.endurance_min)}"
        for g in groups
    ]
    colours = ["#d62728" if g.over_strength else "#1f77b4" for g in groups]
    bars = {
        "type": "bar", "x": [round(g.load_pct_mvc, 2) for g in groups],
        "y": [g.name for g in groups], "orientation": "h", "marker": {"color": colours},
        "hovertext": hover, "hoverinfo": "text",
    }  # fmt: skip
    heading = (
        f"the {len(groups)} most loaded muscle groups"
        if groups
        else "no muscle group carries a load"
    )
    strength = {
        "type": "line", "line": {"dash": "dash", "color": "#d62728", "width": 1},
        "x0": 100, "x1": 100, "xref": "x", "y0": 0, "y1": 1, "yref": "y domain",
    }  # fmt: skip
    top = max([100.0, *(g.load_pct_mvc for g in groups)])
    layout = {
        "template": template("plotly_white"), "height": 60 + 26 * len(groups),
        "font": {"size": 11}, "margin": {"l": 10, "r": 10, "t": 30, "b": 40},
        "title": {"text": heading, "font": {"size": 12}},
        "xaxis": {"title": {"text": "load (%MVC; 100 = strength)"}, "range": [0, 1.05 * top]},
        "yaxis": {"automargin": True}, "shapes": [strength],
    }  # fmt: skip
    return {"data": [bars], "layout": layout}


def _view(case: Case) -> dict[str, Any]:
    """What the page's script needs to draw a case: the body's figure at its postures,
    their labels, the load chart."""
    q = np.stack([posture for _, posture in case.postures])
    steps = np.arange(len(q))
    scene = Scene(case.problem, case.problem.task_objects(), q, steps.tolist())
    figure, moves = body_figure(scene, steps)
    return {
        "figure": figure,
        "labels": [label for label, _ in case.postures],
        "chart": case.chart,
        **moves,
    }


def _case_html(k: int, case: Case) -> str:
    items = "".join(f"<li>{html.escape(line)}</li>" for line in case.lines)
    flags = "".join(f"<li>FLAGGED: {html.escape(f)}</li>" for f in case.flags)
    verdict = (
        f"<ul class='flags'>{flags}</ul>"
        if flags
        else "<p class='ok'>No flags: the answer can be used as it is.</p>"
    )
    return (
        f"<div class='case' data-case='{k}'><h2>{html.escape(case.name)}</h2>"
        f"<ul>{items}</ul>{verdict}</div>"
    )


def page_html(heading: str, subtitle: str, cases: Sequence[Case], index: str = "") -> str:
    """The page of ``cases`` under ``heading``; ``index``: a table whose rows pick a case
    (row k shows case k)."""
    views = [_view(case) for case in cases]
    return PAGE.format(
        title=html.escape(heading),
        subtitle=html.escape(f"{subtitle} · plotly {version()}"),
        index=index,
        summaries="".join(_case_html(k, case) for k, case in enumerate(cases)),
        tables="".join(
            f"<div class='case' data-case='{k}'>{case.tables}</div>" for k, case in enumerate(cases)
        ),
        plotly=plotly_gzip(),
        cases=script_json(views),
        script=scripts("viewer.js", "sortable.js", "posture_page.js"),
    )


def solve_page(answer: StaticAnswer) -> str:
    """report.html of ``solve``."""
    problem = answer.problem
    heading = problem.heading or problem.path.stem
    return page_html(heading, f"{problem_line(problem)} · solve", [solve_case(answer)])


def write_solve_page(answer: StaticAnswer, path: Path) -> Path:
    """``solve``'s report.html into ``path`` (written whole or not at all)."""
    return write_page(solve_page(answer), path)


PAGE = (
    HEAD
    + """
h2 {{ font-size: 1.1em; margin: 0.6em 0 0.2em; }} h3 {{ font-size: 1em; margin: 0.8em 0 0.2em; }}
table {{ border-collapse: collapse; font-size: 0.85em; margin: 0.3em 0; }}
th, td {{ border: 1px solid #ccc; padding: 0.2em 0.5em; white-space: nowrap; }}
th {{ background: #f0f0f0; }} table.sortable th {{ cursor: pointer; }}
th.sorted-up::after {{ content: " ▲"; }} th.sorted-down::after {{ content: " ▼"; }}
#index tbody tr {{ cursor: pointer; }} #index tbody tr.chosen td {{ background: #dbe9f6; }}
details {{ margin: 0.5em 0; }} summary {{ cursor: pointer; font-weight: 600; }}
#body {{ flex: 1 1 520px; height: 720px; min-width: 360px; }}
#side {{ flex: 1 1 480px; min-width: 360px; }}
#postures button {{ margin-right: 0.4em; }} #postures button.shown {{ font-weight: 700; }}
</style></head><body>
<h1>{title}</h1><div class="sub">{subtitle}</div>
{index}
<div id="summaries">{summaries}</div>
<div id="postures" role="group" aria-label="posture shown"></div>
<p id="loading">Loading the plots (this page needs a browser from 2023 or later)...</p>
<div id="views"><div id="body"></div><div id="side"><div id="chart"></div>
<div id="tables">{tables}</div></div></div>
<script id="plotly-gz" type="application/octet-stream">{plotly}</script>
<script id="cases" type="application/json">{cases}</script>
<script>
{script}
</script>
</body></html>
"""
)
