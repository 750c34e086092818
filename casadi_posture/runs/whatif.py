"""Ergonomics what-if queries: a grid over problem keys, run as a batch, with a table and
plots of each outcome against each varied key."""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from casadi_posture.biomech.capability import DESIGN_LIMIT_PCT, PEOPLE, SEXES
from casadi_posture.errors import ProblemError
from casadi_posture.ik.solvers import check_solver
from casadi_posture.problem import load_problem, read_problem_text, text_sha256
from casadi_posture.runs.batch import Case, safe_name
from casadi_posture.spec.overrides import parse_value, split_assignment

#: Outcomes plotted against every varied key, with their axis labels.
OUTCOMES = {
    "task_held_s": "task held (s)",
    "first_fatigue_s": "first group at the fatigue threshold (s)",
    "fatigue_recovery_cycles": "fatigue/recovery cycles",
    "limiting_endurance_at_start_min": "endurance of the limiting group at the start (min)",
    "capable_pct": "capable of the task at the start (% of each sex)",
}
STATIC_OUTCOMES = ("limiting_endurance_at_start_min", "capable_pct")
#: An outcome drawn as several columns of a row, one line each (named in the legend), and
#: the design limit of each (a dashed line; biomech/capability.py).
SERIES = {"capable_pct": {f"capable_{sex}_pct": PEOPLE[sex] for sex in SEXES}}
LIMITS = {"capable_pct": {PEOPLE[sex]: DESIGN_LIMIT_PCT[sex] for sex in SEXES}}

#: What a what-if writes beside a batch's files (``--force`` deletes them).
WHATIF_OUTPUTS = ("whatif.csv", "whatif_*_vs_*.png")


def parse_vary(
    text: str, problem: str | None = None, *, unique: bool = True
) -> tuple[str, list[Any]]:
    """``KEY=V1,V2,...`` -> (key, values); commas inside brackets belong to one value.
    ``problem`` names the file in error messages; ``unique``: each value at most once (a
    paired study may repeat one)."""
    example = "KEY=V1,V2,... such as loads[0].mass_kg=2.5,5"
    key, values = split_assignment(text, "--vary", problem, example)
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
        raise ProblemError(problem, "--vary", text, "no empty value between commas")
    values = [parse_value(p.strip()) for p in parts]
    if unique and len({repr(v) for v in values}) != len(values):
        raise ProblemError(problem, "--vary", text, "each value once")
    if any(isinstance(v, float) for v in values):
        values = [float(v) if isinstance(v, int) and not isinstance(v, bool) else v for v in values]
    return key, values


#: Largest grid run without an explicit ``max_cases``.
MAX_CASES = 1000


def grid(
    problem: str,
    varies: Sequence[tuple[str, list[Any]]],
    *,
    solver: str | None,
    simulate: bool,
    max_cases: int = MAX_CASES,
    paired: bool = False,
    base: Mapping[str, Any] | None = None,
) -> list[Case]:
    """One case per combination of the varied values (with ``paired``, one per position:
    the i-th value of every key together, all lists of one length); ``solver`` may be
    varied too; ``base`` overrides apply to every case first.

    Every combination is validated like a problem file before anything runs, so a bad
    key or value is one error, not a failed case per combination.
    """
    keys = [k for k, _ in varies]
    if len(set(keys)) != len(keys):
        raise ProblemError(problem, "--vary", keys, "each key varied once")
    check_solver(solver, problem)
    empty = [k for k, values in varies if not values]
    if empty:
        raise ProblemError(problem, "--vary", empty[0], "at least one value per varied key")
    lengths = {k: len(values) for k, values in varies}
    if paired and len(set(lengths.values())) > 1:
        raise ProblemError(problem, "--vary", lengths, "lists of one length with --paired")
    combos = (
        list(zip(*(values for _, values in varies), strict=True))
        if paired
        else list(itertools.product(*(values for _, values in varies)))
    )
    if len({repr(c) for c in combos}) != len(combos):
        raise ProblemError(problem, "--vary", keys, "each combination of values once")
    count = len(combos)
    if count > max_cases:
        raise ProblemError(
            problem,
            "--vary",
            f"{count} cases",
            f"at most {max_cases} cases; pass --max-cases {count} to run them all",
        )
    for value in dict(varies).get("solver", []):
        check_solver(value, problem, "--vary solver")
    text = read_problem_text(problem)
    cases = []
    for combo in combos:
        chosen = dict(base or {}) | dict(zip(keys, combo, strict=True))
        case_solver = chosen.pop("solver", solver)
        name = safe_name("__".join(f"{k}={v}" for k, v in zip(keys, combo, strict=True)))
        try:
            load_problem(problem, chosen, text=text)
        except ProblemError as error:
            given = ", ".join(f"{k}={v}" for k, v in chosen.items())
            raise ProblemError(
                problem, error.key, error.value, f"{error.expected} (set by --vary {given})"
            ) from None
        cases.append(Case(name or "base", problem, chosen, case_solver, simulate, text))
    return cases


def describe_grid(
    problem: str, varies: Sequence[tuple[str, list[Any]]], *, solver: str | None, simulate: bool
) -> dict[str, Any]:
    """What a what-if run was asked for, recorded in its folder so --resume can check it."""
    text = read_problem_text(problem)
    return {
        "kind": "whatif",
        "problem": problem,
        "problem_sha256": text_sha256(text),
        "vary": {key: values for key, values in varies},
        "solver": solver,
        "static": not simulate,
    }


def plot_outcomes(
    rows: Sequence[dict[str, Any]],
    varies: Sequence[tuple[str, list[Any]]],
    out: Path,
    *,
    simulate: bool,
) -> list[Path]:
    """One figure per outcome and varied key: the outcome against that key's values, one
    line per combination of the other keys (the share capable: one per sex too, with its
    design limit dotted). Flagged cases (level 1 not reached, over strength, a solver
    failure) are crossed out in red; a task held to the end of the run is a lower bound,
    drawn as an upward triangle."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outcomes = OUTCOMES if simulate else {k: OUTCOMES[k] for k in STATIC_OUTCOMES}
    keys = [k for k, _ in varies]
    ran = [r for r in rows if r["status"] in ("ok", "flagged")]
    paths = []
    for outcome, label in outcomes.items():
        for key, values in varies:
            others = [k for k in keys if k != key]
            fig, ax = plt.subplots(figsize=(6.0, 4.0), dpi=110)
            given = {k: [str(v) for v in values] for k, values in varies}
            groups = sorted(
                {tuple(str(_value(r, k)) for k in others) for r in ran},
                key=lambda g: [
                    given[k].index(v) if v in given[k] else -1
                    for k, v in zip(others, g, strict=True)
                ],
            )
            series = SERIES.get(outcome, {outcome: ""})
            for (g, group), (s, (column, sex)) in itertools.product(
                enumerate(groups), enumerate(series.items())
            ):
                members = [r for r in ran if tuple(str(_value(r, k)) for k in others) == group]
                members.sort(key=lambda r: _position(r, key, values))
                xs = np.array([_position(r, key, values) for r in members], dtype=float)
                ys = np.array([_number(r.get(column)) for r in members])
                name = ", ".join(
                    [sex] * bool(sex) + [f"{k}={v}" for k, v in zip(others, group, strict=True)]
                )
                style = ("-o", "--s")[s % 2]  # one colour per combination, one style per sex
                color = f"C{g % 10}" if len(series) > 1 else None
                (line,) = ax.plot(xs, ys, style, color=color, label=name or None)
                bound = np.array(
                    [
                        outcome == "task_held_s" and bool(r.get("task_held_is_lower_bound"))
                        for r in members
                    ]
                )
                if bound.any():
                    ax.plot(xs[bound], ys[bound], "^", ms=10, mfc="none", color=line.get_color())
                flagged = np.array([r["status"] == "flagged" for r in members])
                if flagged.any():
                    ax.plot(xs[flagged], ys[flagged], "x", ms=11, mew=2, color="tab:red")
            if any(r.get("task_held_is_lower_bound") for r in ran) and outcome == "task_held_s":
                ax.plot([], [], "^", mfc="none", color="0.3", label="held to the end (lower bound)")
            for sex, limit in LIMITS.get(outcome, {}).items():
                ax.axhline(limit, ls=":", lw=1.2, color="0.35")
                ax.annotate(
                    f"{sex}: design limit {limit:g} % (a convention)",
                    (0.99, limit),
                    xycoords=("axes fraction", "data"),
                    xytext=(0, -9),
                    textcoords="offset points",
                    fontsize=7,
                    color="0.35",
                    ha="right",
                )
            if outcome in LIMITS:
                ax.set_ylim(0.0, 102.0)
            if any(r["status"] == "flagged" for r in ran):
                ax.plot([], [], "x", mew=2, color="tab:red", label="flagged: see whatif.csv")
            if not _numeric(values):
                ax.set_xticks(range(len(values)), [str(v) for v in values])
            ax.set_xlabel(key)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7)
            fig.tight_layout()
            path = out / f"whatif_{outcome}_vs_{safe_name(key)}.png"
            fig.savefig(path)
            plt.close(fig)
            paths.append(path)
    return paths


def _position(row: dict[str, Any], key: str, values: Sequence[Any]) -> float:
    """Where a case sits on the x axis: its value, or the value's index for text values."""
    value = _value(row, key)
    return float(value) if _numeric(values) else float(values.index(value))


def _number(value: Any) -> float:
    """A plotted outcome: None (unlimited, never) is not drawn."""
    return np.nan if value is None else float(value)


def _value(row: dict[str, Any], key: str) -> Any:
    return row.get("solver") if key == "solver" else row.get(key)


def _numeric(values: Sequence[Any]) -> bool:
    return all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
