"""The solved posture over a grid of cases, for prose that quotes a joint's angle
(``posture problem=PATH grid='KEYS=V1,V2,...|KEYS=V1,...'``: each ``|``-separated axis ties
its comma-separated keys to one value, as ``whatif --vary`` does)."""

from __future__ import annotations

import itertools
from typing import Any

import casadi_posture as cp

from . import runs
from .regions import Region
from .session import Session


def axes(grid: str) -> list[tuple[list[str], list[str]]]:
    """``'a,b=1,2|c=3'`` → ``[(['a', 'b'], ['1', '2']), (['c'], ['3'])]``."""
    found = []
    for axis in filter(None, grid.split("|")):
        keys, _, values = axis.partition("=")
        found.append((keys.split(","), values.split(",")))
    return found


def values(region: Region, session: Session) -> dict[str, Any]:
    """``deg[V][DOF]``: ``min`` and ``max`` of each DOF's solved angle [deg] over the cases
    whose first axis takes the value ``V`` (as written in ``grid=``)."""
    grid = axes(region.args["grid"])
    base = runs.problem(region, session)
    angles: dict[str, dict[str, list[float]]] = {}
    for case in itertools.product(*(values for _, values in grid)):
        keys = {
            k: runs.overrides(f"x={v}")["x"]
            for (ks, _), v in zip(grid, case, strict=True)
            for k in ks
        }
        answer = cp.solve(cp.from_dict(base.data, str(base.path), keys))
        for dof, angle in answer.posture_deg.items():
            angles.setdefault(case[0], {}).setdefault(dof, []).append(angle)
    return {
        "deg": {
            v: {dof: {"min": min(a), "max": max(a)} for dof, a in by_dof.items()}
            for v, by_dof in angles.items()
        }
    }
