"""The values of one run, for the prose beside a console block or a Python example:
``summary file=PATH`` reads a ``summary.json`` the document's own commands wrote, ``table
file=PATH`` a CSV table they wrote;
``simulate problem=PATH set='KEY=VALUE;...'`` and ``solve problem=PATH`` run a problem of
the document's working folder."""

from __future__ import annotations

import csv
import json
import re
from typing import Any

import casadi_posture as cp

from .regions import Region
from .session import Session


def with_asymmetry(summary: dict[str, Any]) -> dict[str, Any]:
    """The summary's keys and ``asymmetry_deg``: the largest left/right difference of its
    key postures [deg] (None for a task that is not mirror-symmetric)."""
    apart = [p["asymmetry_deg"] for p in summary["plausibility"]["postures"] if p["asymmetry_deg"]]
    return summary | {"asymmetry_deg": max(apart, default=None)}


def summary(region: Region, session: Session) -> dict[str, Any]:
    """A ``summary.json`` of the working folder (``file=``), :func:`with_asymmetry`, and
    ``groups``: its ``half_joints`` by name."""
    found = with_asymmetry(json.loads((session.folder / region.args["file"]).read_text()))
    return found | {"groups": {h["half_joint"]: h for h in found["half_joints"]}}


def number(cell: str) -> float | str:
    """A CSV cell as a number where it is one."""
    try:
        return float(cell)
    except ValueError:
        return cell


#: The plausibility flag of a trunk leaning back, with its lumbar extension [deg].
LEAN = re.compile(r"the trunk leans back \((\d+)° of lumbar extension\)")


def table(region: Region, session: Session) -> dict[str, Any]:
    """A CSV table of the working folder (``file=``): ``rows``, each a dict by column, and
    ``leans_deg``, the least and most lumbar extension [deg] its ``flags`` name (None
    when no row is flagged for a trunk leaning back)."""
    with (session.folder / region.args["file"]).open(newline="") as handle:
        rows = [{k: number(v) for k, v in row.items()} for row in csv.DictReader(handle)]
    leans = [int(a) for row in rows for a in LEAN.findall(str(row.get("flags", "")))]
    return {"rows": rows, "leans_deg": (min(leans), max(leans)) if leans else None}


def overrides(text: str) -> dict[str, Any]:
    """``'a=1;b.c=x'`` → ``{"a": 1, "b.c": "x"}`` (values read as JSON where they parse)."""
    found: dict[str, Any] = {}
    for item in filter(None, text.split(";")):
        key, _, value = item.partition("=")
        try:
            found[key] = json.loads(value)
        except json.JSONDecodeError:
            found[key] = value
    return found


def listed(items: list[str]) -> str:
    """'a, b and c'."""
    return " and ".join([", ".join(items[:-1]), items[-1]] if len(items) > 1 else items)


def problem(region: Region, session: Session) -> cp.Problem:
    """The region's ``problem=`` of the working folder, with its ``set=`` keys."""
    return cp.load(session.folder / region.args["problem"], overrides(region.args.get("set", "")))


def simulate(region: Region, session: Session) -> dict[str, Any]:
    """The problem simulated: its summary (:func:`with_asymmetry`) and ``at``, each whole
    second's timeline row by its time [s] (``{at[90][shoulder_flexion_deg]:.1f}``),
    ``at_end``, the last row, ``duration_min``, ``recoveries_min``, the recoveries'
    times [min] as text, and ``most_tired``, the half-joint whose fatigue rose highest."""
    run = cp.simulate(problem(region, session))
    frame = run.to_frame()
    rows = frame[frame["time_s"] == frame["time_s"].round()]
    groups = run.summary()["half_joints"]
    return with_asymmetry(run.summary()) | {
        "most_tired": max(groups, key=lambda g: g["max_fatigue"]),
        "at": {int(row["time_s"]): row for row in rows.to_dict("records")},
        "at_end": frame.iloc[-1].to_dict(),
        "duration_min": run.summary()["duration_s"] / 60,
        "recoveries_min": listed(
            [f"{p['time_s'] / 60:.1f}" for p in run.summary()["recovery_postures"]]
        ),
    }


def solve(region: Region, session: Session) -> dict[str, Any]:
    """The problem's posture solved: ``groups``, each half-joint's row of
    :meth:`to_frame` by name (strength and torque [N·m], load [%MVC], endurance [min]),
    and ``capable_pct``, the share of each sex capable [%] by sex."""
    answer = cp.solve(problem(region, session))
    frame = answer.to_frame().set_index("name")
    shares = {sex: answer.capable.share(sex) for sex in ("male", "female")}
    return {"groups": frame.to_dict("index"), "capable_pct": shares}
