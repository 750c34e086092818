"""RULA and REBA in the outputs (docs/rula_reba.md): the console lines and JSON of a static
answer, a run's scores per step (timeline columns), its summary.json section, and the
worst scores of a batch or what-if row."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from casadi_posture.ergonomics.posture_scores import NOT_SCORED, SideScores
from casadi_posture.output.key_postures import recoveries
from casadi_posture.output.per_run import once_per_run
from casadi_posture.problem import Problem
from casadi_posture.simulation import SimulationResult
from casadi_posture.static import posture_scores

#: The sides' names in words.
SIDES = {"r": "right", "l": "left", "arm": "arm"}

Scores = tuple[SideScores, ...]


def inputs(problem: Problem, scores: Scores) -> dict[str, Any]:
    """The inputs the body cannot give: those the file's ``[ergonomics]`` set (with their
    values) and those assumed; a note instead of scores for a body they do not fit."""
    return {
        "from_problem_file": problem.spec.ergonomics.given(),
        "assumed": list(scores[0].assumed) if scores else [],
        "note": None if scores else f"not scored: {NOT_SCORED}",
    }


def static_report(problem: Problem, scores: Scores) -> dict[str, Any]:
    """A static answer's RULA and REBA as ``--json`` gives them: every score per side."""
    return {"sides": [s.to_dict() for s in scores], **inputs(problem, scores)}


def lines(problem: Problem, scores: Scores) -> list[str]:
    """The console lines of a static answer: per side RULA's grand score and action level,
    REBA's score and risk level; the inputs from the file and the assumed ones, once."""
    given = inputs(problem, scores)
    if not scores:
        return [f"RULA/REBA: {given['note']}"]
    out = ["RULA and REBA of the posture (docs/rula_reba.md):"]
    out += [f"  {SIDES[s.side]}: {side_words(s)}" for s in scores]
    if given["from_problem_file"]:
        items = ", ".join(f"{k} = {_toml(v)}" for k, v in given["from_problem_file"].items())
        out.append(f"  from the problem's [ergonomics]: {items}")
    out.append(f"  assumed: {', '.join(given['assumed'])}")
    return out


def side_words(side: SideScores) -> str:
    """``RULA 4 (action level 2: ...); REBA 2, low risk (action level 1: ...)``."""
    r, b = side.rula, side.reba
    return (
        f"RULA {r.grand} (action level {r.action_level}: {r.action}); REBA {b.reba}, "
        f"{b.risk} risk (action level {b.action_level}: action {b.action})"
    )


def _toml(value: Any) -> str:
    return str(value).lower() if isinstance(value, bool) else repr(value)


@once_per_run
def step_scores(result: SimulationResult) -> list[Scores | None]:
    """RULA and REBA per side at every step of a run holding its loads (a recording: those
    each frame holds; None on a rest step: the relaxed posture is not modelled). A posture
    met before with the same loads is not scored again."""
    tl, problem = result.timeline, result.problem
    seen: dict[bytes, Scores] = {}
    out: list[Scores | None] = []
    held = [None] * tl.time.size if tl.held is None else list(tl.held)
    for q, phase, loads in zip(tl.q, tl.phase, held, strict=True):
        if phase == "rest":
            out.append(None)
            continue
        key = q.tobytes() + (b"" if loads is None else loads.tobytes())
        if key not in seen:
            seen[key] = posture_scores(problem, q, loads)
        out.append(seen[key])
    return out


def timeline_columns(
    result: SimulationResult, steps: Sequence[Scores | None]
) -> dict[str, list[int | None]]:
    """``rula_<side>`` and ``reba_<side>`` per step of ``steps`` (``step_scores``;
    ``rula``, ``reba`` for a planar arm; none for a body not scored)."""
    scored = next((s for s in steps if s), None)
    if scored is None:
        return {}
    columns: dict[str, list[int | None]] = {}
    for i, side in enumerate(scored):
        suffix = "" if side.side == "arm" else f"_{side.side}"
        columns[f"rula{suffix}"] = [None if s is None else s[i].rula.grand for s in steps]
        columns[f"reba{suffix}"] = [None if s is None else s[i].reba.reba for s in steps]
    return columns


def run_report(result: SimulationResult, steps: Sequence[Scores | None]) -> dict[str, Any]:
    """summary.json's ``rula_reba``: the scores and action levels per side at the start,
    each recovery and the end (on a rest step: the last held posture's), the worst over the
    run with its side and first time [s], and the inputs (``inputs``)."""
    tl, problem = result.timeline, result.problem
    held = [k for k, s in enumerate(steps) if s]
    report: dict[str, Any] = {"postures": [], "worst": None}
    if held:
        marks = [(0, "start"), *((s, "recovery") for s in recoveries(result))]
        marks.append((tl.time.size - 1, "end"))
        for step, label in marks:
            last = steps[held[int(np.searchsorted(held, step, side="right")) - 1]] or ()
            report["postures"].append(
                {
                    "posture": label,
                    "time_s": float(tl.time[step]),
                    "phase": tl.phase[step],
                    "sides": {s.side: brief(s) for s in last},
                }
            )
        report["worst"] = worst((float(tl.time[k]), side) for k in held for side in steps[k] or ())
    scored = steps[held[0]] if held else posture_scores(problem, problem.posture)
    return report | inputs(problem, scored or ())


def run_lines(report: dict[str, Any]) -> list[str]:
    """A run's console lines from its summary's ``rula_reba``: each side's RULA and REBA at
    the start and the end, and the worst of each with its action level, side and time."""
    if report["worst"] is None:
        return [f"  RULA/REBA: {report['note']}"] if report["note"] else []

    def at(posture: dict[str, Any]) -> str:
        sides = posture["sides"].items()
        return ", ".join(f"{SIDES[k]} {v['rula']} / {v['reba']}" for k, v in sides)

    rula, reba = report["worst"]["rula"], report["worst"]["reba"]
    return [
        f"  RULA / REBA at the start: {at(report['postures'][0])}; at the end: "
        f"{at(report['postures'][-1])}",
        f"  worst RULA {rula['score']} (action level {rula['action_level']}, "
        f"{SIDES[rula['side']]}) from {rula['time_s']:g} s; worst REBA {reba['score']} "
        f"({reba['risk']} risk, {SIDES[reba['side']]}) from {reba['time_s']:g} s",
    ]


def brief(side: SideScores) -> dict[str, Any]:
    """One side's RULA and REBA with their action levels and words."""
    r, b = side.rula, side.reba
    return {
        "rula": r.grand,
        "rula_action_level": r.action_level,
        "rula_action": r.action,
        "reba": b.reba,
        "reba_action_level": b.action_level,
        "reba_risk": b.risk,
        "reba_action": b.action,
    }


def worst(candidates: Iterable[tuple[float, SideScores]]) -> dict[str, Any] | None:
    """The highest RULA and REBA among (time [s], one side's scores), each with its action
    level, the side and the first time it was reached; None when there is none."""
    items = list(candidates)
    if not items:
        return None
    t, s = max(items, key=lambda ts: (ts[1].rula.grand, -ts[0]))
    rula = {"score": s.rula.grand, "action_level": s.rula.action_level, "action": s.rula.action}
    out = {"rula": {**rula, "side": s.side, "time_s": t}}
    t, s = max(items, key=lambda ts: (ts[1].reba.reba, -ts[0]))
    reba = {"score": s.reba.reba, "action_level": s.reba.action_level, "risk": s.reba.risk}
    out["reba"] = {**reba, "action": s.reba.action, "side": s.side, "time_s": t}
    return out


def row(highest: dict[str, Any] | None) -> dict[str, Any]:
    """The worst RULA and REBA (``worst``) as row fields, with their action levels and
    REBA's risk; None when nothing was scored."""
    if highest is None:
        return dict.fromkeys(ROW_KEYS)
    rula, reba = highest["rula"], highest["reba"]
    return {
        "worst_rula": rula["score"],
        "worst_rula_action_level": rula["action_level"],
        "worst_reba": reba["score"],
        "worst_reba_action_level": reba["action_level"],
        "worst_reba_risk": reba["risk"],
    }


#: The row fields of ``row``.
ROW_KEYS = (
    "worst_rula",
    "worst_rula_action_level",
    "worst_reba",
    "worst_reba_action_level",
    "worst_reba_risk",
)
