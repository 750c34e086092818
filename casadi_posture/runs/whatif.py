"""Ergonomics what-if queries: a grid over problem keys (keys tied to one value count as
one axis), run as a batch; runs/whatif_plots.py draws its figures."""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Mapping, Sequence
from typing import Any

from casadi_posture.errors import ProblemError
from casadi_posture.ik.solvers import check_solver
from casadi_posture.output.axes import SOLVER, axis_keys, check_units
from casadi_posture.problem import load_problem, read_problem_text, text_sha256
from casadi_posture.runs.batch import Case, safe_name
from casadi_posture.spec.overrides import parse_value

#: What a what-if writes beside a batch's files (``--force`` deletes them).
WHATIF_OUTPUTS = ("whatif.csv", "whatif_*_vs_*.png", "report.html")


def parse_vary(
    text: str, problem: str | None = None, *, unique: bool = True
) -> tuple[str, list[Any]]:
    """``KEY=V1,V2,...`` -> (axis, values); ``KEY1,KEY2=V1,...`` ties the keys to one value
    (axis ``KEY1,KEY2``); commas inside brackets belong to one value. ``problem`` names the
    file in error messages; ``unique``: each value at most once (a paired study may repeat
    one)."""
    example = "KEY=V1,V2,... such as loads[0].mass_kg=2.5,5 (KEY1,KEY2=... ties keys)"
    axis, sep, values = text.partition("=")
    if not sep or not axis or not values:
        raise ProblemError(problem, "--vary", text, example)
    key = ",".join(axis_keys(axis, problem))
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
    values = [parse_value(p.strip(), problem, "--vary") for p in parts]
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
    the i-th value of every axis together, all lists of one length); an axis ``KEY1,KEY2``
    gives its keys one value; ``solver`` may be varied too; ``base`` overrides apply to
    every case first.

    Every combination is validated like a problem file before anything runs, so a bad
    key or value is one error, not a failed case per combination.
    """
    tied = [axis_keys(axis, problem) for axis, _ in varies]
    keys = [key for group in tied for key in group]
    if len(set(keys)) != len(keys):
        raise ProblemError(problem, "--vary", keys, "each key varied once")
    check_solver(solver, problem)
    empty = [axis for axis, values in varies if not values]
    if empty:
        raise ProblemError(problem, "--vary", empty[0], "at least one value per varied key")
    lengths = {axis: len(values) for axis, values in varies}
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
    for value in dict(varies).get(SOLVER, []):
        check_solver(value, problem, "--vary solver")
    text = read_problem_text(problem)
    cases = []
    for name, combo in zip(case_names(tied, combos), combos, strict=True):
        chosen = dict(base or {}) | {
            key: value for group, value in zip(tied, combo, strict=True) for key in group
        }
        case_solver = chosen.pop(SOLVER, solver)
        _validated(problem, chosen, text)
        if not cases:  # an unknown key is named before the unit of the keys it is tied to
            for group in tied:
                check_units(group, problem)
        cases.append(Case(name, problem, chosen, case_solver, simulate, text))
    return cases


#: Longest case name (a folder's); a longer one is cut and ends in a digest of its values.
MAX_NAME = 80


def case_names(tied: Sequence[Sequence[str]], combos: Sequence[Sequence[Any]]) -> list[str]:
    """Each case's name, ``mass_kg=6,target_m_2=1.2``: per axis its label (``axis_labels``)
    and its value, safe as a folder name; a name two cases would share (values that differ
    only in characters a folder name cannot hold) or longer than ``MAX_NAME`` is cut and
    ends in a digest of its values, so every name is unique and the same on every run of
    the grid (``--resume``); ``base`` for a grid without axes."""
    labels = axis_labels(tied)
    names = [
        safe_name(",".join(f"{a}={_shown(v)}" for a, v in zip(labels, combo, strict=True)))
        or "base"
        for combo in combos
    ]
    taken = {name: names.count(name) for name in names}
    return [
        name
        if len(name) <= MAX_NAME and taken[name] == 1
        else f"{name[: MAX_NAME - 9]}-{hashlib.sha1(repr(combo).encode()).hexdigest()[:8]}"
        for name, combo in zip(names, combos, strict=True)
    ]


def axis_labels(tied: Sequence[Sequence[str]]) -> list[str]:
    """A short label per axis: the last part of its keys (``loads[0].mass_kg`` ->
    ``mass_kg``, ``tasks[2].target_m[2]`` -> ``target_m_2``), with more parts where two
    axes would share one; keys tied to one value that share a label give it once, others
    are joined by ``+``."""
    parts = [[key.split(".") for key in group] for group in tied]
    depth = [1] * len(tied)

    def label(k: int) -> str:
        shown = (".".join(p[-depth[k] :]) for p in parts[k])
        return "+".join(dict.fromkeys(shown)).replace("[", "_").replace("]", "")

    while True:
        labels = [label(k) for k in range(len(tied))]
        clash = [k for k, text in enumerate(labels) if labels.count(text) > 1]
        deeper = [k for k in clash if depth[k] < max(len(p) for p in parts[k])]
        if not deeper:
            return labels
        for k in deeper:
            depth[k] += 1


def _shown(value: Any) -> str:
    """A varied value in a case name: ``6`` for 6.0, ``0.5_0_1.2`` for a list."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        short = f"{value:g}"
        return short if float(short) == value else repr(value)
    if isinstance(value, list):
        return "_".join(_shown(v) for v in value)
    return str(value)


def _validated(problem: str, chosen: dict[str, Any], text: str) -> None:
    """The problem with the ``chosen`` overrides is valid, or one error naming them."""
    try:
        load_problem(problem, chosen, text=text)
    except ProblemError as error:
        given = ", ".join(f"{k}={v}" for k, v in chosen.items())
        raise ProblemError(
            problem, error.key, error.value, f"{error.expected} (set by --vary {given})"
        ) from None


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
