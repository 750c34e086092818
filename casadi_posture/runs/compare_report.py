"""report.html of ``compare``: a row per problem (a click on it shows that problem), and per
problem the start and both solvers' postures, the verdict, the levels side by side and the
DOFs by their difference (the page of output/posture_page.py)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from casadi_posture.output.html_page import table, write_page
from casadi_posture.output.posture_page import Case, page_html, section
from casadi_posture.problem import Problem
from casadi_posture.runs.compare import Comparison, Starts, amount
from casadi_posture.static import level_outcome


def compare_case(problem: Problem, comparison: Comparison, flags: Sequence[str]) -> Case:
    """The page's case of a solver comparison: the start and both solvers' postures, the
    verdict, the levels side by side and the DOFs by their difference."""
    ns, lx = comparison.nullspace, comparison.lexicographic
    lines = [f"verdict: {comparison.verdict}"]
    if comparison.starts is not None:
        lines.append(comparison.starts.line())
    lines.append(f"largest joint difference: {comparison.max_joint_difference_deg:.3g} deg")
    lines += [
        f"{r.solver}: {r.status}, {r.iterations} iterations, {1e3 * r.wall_time_s:.1f} ms"
        for r in (ns, lx)
    ]
    levels = table(
        ["level", "tasks", "unit", "residual nullspace", "residual lexicographic",
         "achieved nullspace", "achieved lexicographic"],
        [[k + 1, name, comparison.units[k], ns.residuals[k], lx.residuals[k],
          *(level_outcome(r.achieved[k], k == comparison.criterion) for r in (ns, lx))]
         for k, name in enumerate(comparison.levels)],
    )  # fmt: skip
    a, b = np.degrees(ns.q), np.degrees(lx.q)
    order = np.argsort(-np.abs(a - b), kind="stable")
    dofs = table(
        ["DOF", "start (deg)", "nullspace (deg)", "lexicographic (deg)", "difference (deg)"],
        [[comparison.dofs[i], math.degrees(problem.posture[i]), a[i], b[i], a[i] - b[i]]
         for i in order],
        **{"class": "sortable"},
    )  # fmt: skip
    return Case(
        name=comparison.problem,
        problem=problem,
        postures=(
            ("start (posture_deg)", np.asarray(problem.posture, dtype=float)),
            ("nullspace", ns.q),
            ("lexicographic", lx.q),
        ),
        lines=tuple(lines),
        flags=tuple(flags),
        tables=section("Priority levels", levels) + section("DOFs", dofs, closed=True),
    )


#: The index's columns of the random starts (``compare --starts``).
STARTS_HEADERS = ["random starts", "agree", "reach the task", "local minimum", "unreachable",
                  "differ", "worst joint diff (deg)", "worst residual gap"]  # fmt: skip


def _starts_cells(starts: Starts | None) -> list[object]:
    """A problem's cells under ``STARTS_HEADERS`` (blank without random starts)."""
    if starts is None:
        return [""] * len(STARTS_HEADERS)
    return [starts.count, starts.agree, starts.reached, starts.local_minimum, starts.unreachable,
            starts.differ, starts.worst_joint_difference_deg,
            amount(starts.worst_residual_gap, starts.worst_gap_unit)]  # fmt: skip


def compare_page(pairs: Sequence[tuple[Problem, Comparison, Sequence[str]]]) -> str:
    """report.html of ``compare``: a row per problem (a click shows it), then the chosen
    problem's postures, verdict and tables; ``pairs``: each problem, its comparison and
    its flags."""
    rows = [
        [c.problem, len(c.dofs), len(c.levels), c.verdict, c.max_joint_difference_deg,
         1e3 * c.nullspace.wall_time_s, 1e3 * c.lexicographic.wall_time_s]
        for _, c, _ in pairs
    ]  # fmt: skip
    headers = ["problem", "DOFs", "levels", "verdict", "max joint diff (deg)",
               "time nullspace (ms)", "time lexicographic (ms)"]  # fmt: skip
    if any(c.starts is not None for _, c, _ in pairs):
        headers += STARTS_HEADERS
        for row, (_, c, _) in zip(rows, pairs, strict=True):
            row += _starts_cells(c.starts)
    index = table(headers, rows, id="index", **{"class": "sortable"})
    agree = sum(c.agree for _, c, _ in pairs)
    heading = f"Both IK solvers on {len(pairs)} problem(s): {agree} agree"
    cases = [compare_case(problem, c, flags) for problem, c, flags in pairs]
    note = "<p class='sub'>Click a problem's row to see its postures and tables.</p>"
    return page_html(heading, "compare", cases, note + index)


def write_compare_page(
    pairs: Sequence[tuple[Problem, Comparison, Sequence[str]]], path: Path
) -> Path:
    """``compare``'s report.html into ``path`` (written whole or not at all)."""
    return write_page(compare_page(pairs), path)
