"""Ergonomics what-if queries: a grid over problem keys, run as a batch, with a table and
plots of each outcome against each varied key (SPEC §9)."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .batch import Case, safe_name
from .errors import ProblemError
from .overrides import parse_key, parse_value
from .problem import read_problem_text

#: Outcomes plotted against every varied key, with their axis labels.
OUTCOMES = {
    "task_held_s": "task held (s)",
    "first_fatigue_s": "first group at the fatigue threshold (s)",
    "fatigue_recovery_cycles": "fatigue/recovery cycles",
    "limiting_endurance_min": "endurance of the limiting group at the start (min)",
}
STATIC_OUTCOMES = ("limiting_endurance_min",)


def parse_vary(text: str) -> tuple[str, list[Any]]:
    """``KEY=V1,V2,...`` -> (key, values); commas inside brackets belong to one value."""
    key, sep, values = text.partition("=")
    if not sep or not key or not values:
        raise ProblemError(None, "--vary", text, "KEY=V1,V2,... such as loads[0].mass_kg=2.5,5")
    parse_key(key)
    parts: list[str] = []
    depth, current = 0, ""
    for char in values:
        depth += char == "["
        depth -= char == "]"
        if char == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += char
    parts.append(current)
    if any(not p.strip() for p in parts):
        raise ProblemError(None, "--vary", text, "no empty value between commas")
    values = [parse_value(p.strip()) for p in parts]
    if any(isinstance(v, float) for v in values):
        values = [float(v) if isinstance(v, int) and not isinstance(v, bool) else v for v in values]
    return key, values


def grid(
    problem: str,
    varies: Sequence[tuple[str, list[Any]]],
    *,
    solver: str | None,
    simulate: bool,
) -> list[Case]:
    """One case per combination of the varied values; ``solver`` may be varied too."""
    keys = [k for k, _ in varies]
    if len(set(keys)) != len(keys):
        raise ProblemError(None, "--vary", keys, "each key varied once")
    text = read_problem_text(problem)
    cases = []
    for combo in itertools.product(*(values for _, values in varies)):
        chosen = dict(zip(keys, combo, strict=True))
        case_solver = chosen.pop("solver", solver)
        name = safe_name("__".join(f"{k}={v}" for k, v in zip(keys, combo, strict=True)))
        cases.append(Case(name or "base", problem, chosen, case_solver, simulate, text))
    return cases


def plot_outcomes(
    rows: Sequence[dict[str, Any]],
    varies: Sequence[tuple[str, list[Any]]],
    out: Path,
    *,
    simulate: bool,
) -> list[Path]:
    """One figure per outcome and varied key: the outcome against that key's values, one
    line per combination of the other keys."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outcomes = OUTCOMES if simulate else {k: OUTCOMES[k] for k in STATIC_OUTCOMES}
    keys = [k for k, _ in varies]
    ok = [r for r in rows if r["status"] == "ok"]
    paths = []
    for outcome, label in outcomes.items():
        for key, values in varies:
            others = [k for k in keys if k != key]
            fig, ax = plt.subplots(figsize=(6.0, 4.0), dpi=110)
            groups = sorted({tuple(str(r.get(k)) for k in others) for r in ok})
            for group in groups:
                members = [r for r in ok if tuple(str(r.get(k)) for k in others) == group]
                xs = [
                    values.index(_value(r, key)) if not _numeric(values) else _value(r, key)
                    for r in members
                ]
                ys = [np.nan if r.get(outcome) is None else r[outcome] for r in members]
                order = np.argsort(xs)
                name = ", ".join(f"{k}={v}" for k, v in zip(others, group, strict=True))
                ax.plot(
                    np.asarray(xs)[order],
                    np.asarray(ys, dtype=float)[order],
                    "-o",
                    label=name or None,
                )
            if not _numeric(values):
                ax.set_xticks(range(len(values)), [str(v) for v in values])
            ax.set_xlabel(key)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
            if others:
                ax.legend(fontsize=7)
            fig.tight_layout()
            path = out / f"whatif_{outcome}_vs_{safe_name(key)}.png"
            fig.savefig(path)
            plt.close(fig)
            paths.append(path)
    return paths


def _value(row: dict[str, Any], key: str) -> Any:
    return row.get("solver") if key == "solver" else row.get(key)


def _numeric(values: Sequence[Any]) -> bool:
    return all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
