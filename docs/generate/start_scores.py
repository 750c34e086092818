"""docs/rula_reba.md: RULA and REBA of the shipped 3-D problems' start postures
(``start-scores``), as ``solve`` scores them, and over a shipped run (``run-scores``)."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp

from . import shipped_runs
from .regions import Region
from .session import Session

#: The shipped 3-D problems in the page's order; problems whose scores are the same are
#: merged into one row.
STEMS = (
    "standing_shelf_box",
    "standing_overhead_drill",
    "standing_wall_m25",
    "standing_wall_m45",
    "standing_wall_horizontal",
    "seated_assembly",
)


def scores(stem: str, session: Session) -> str:
    """'| 6, 6 | 4, 4 (medium) |': RULA grand and REBA of the right and left sides, REBA's
    risk once when both sides share it."""
    answer = cp.solve(cp.load(session.folder / "problems" / f"{stem}.toml"))
    sides = {s.side: s for s in answer.scores}
    rula = ", ".join(str(sides[s].rula.grand) for s in ("r", "l"))
    reba = ", ".join(str(sides[s].reba.reba) for s in ("r", "l"))
    risks = {sides[s].reba.risk for s in ("r", "l")}
    return f"| {rula} | {reba}{f' ({risks.pop()})' if len(risks) == 1 else ''} |"


def table(region: Region, session: Session) -> str:
    """The table: one row per problem of :data:`STEMS`, those with the same scores merged
    ('`standing_wall_m25` (and `_m45`, `_horizontal`)')."""
    merged: dict[str, list[str]] = {}
    for stem in STEMS:
        merged.setdefault(scores(stem, session), []).append(stem)
    rows = ["| problem | RULA grand | REBA |", "| --- | --- | --- |"]
    for cells, stems in merged.items():
        first, rest = stems[0], [s.removeprefix(stems[0].rsplit("_", 1)[0]) for s in stems[1:]]
        label = f"`{first}`" + (f" (and {', '.join(f'`{r}`' for r in rest)})" if rest else "")
        rows.append(f"| {label} {cells}")
    return "\n".join(rows)


def run_scores(region: Region, session: Session) -> dict[str, Any]:
    """RULA and REBA of the run of the shipped problem ``problem=`` (a name of
    :data:`shipped_runs.STEMS`) as shipped: ``start[SIDE]`` (its scores at the start, by
    side) and ``worst`` (the worst of the run: ``rula`` and ``reba``, each with its
    ``score``, ``action_level`` and ``action``)."""
    scores = shipped_runs.summary(region.args["problem"], "shipped")["rula_reba"]
    start = next(p for p in scores["postures"] if p["posture"] == "start")
    return {"start": start["sides"], "worst": scores["worst"]}
