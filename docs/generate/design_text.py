"""docs/design.md and docs/workflows.md: the prose around the designs of the standing shelf,
as ``casadi_posture.workplace_design.design`` finds them (``design``).

``design problem=PATH NAME='OBJECTIVE KEY=LO:HI;KEY=LO:HI' ...`` designs a shipped
problem once for each NAME, with ``--objective OBJECTIVE`` and each ``--free`` given (in
a process of its own: a design two documents quote runs once); the template reads
``{NAME[best]}``. ``sweep=NAME`` adds that design's sweep of ``design.png`` over its one
free quantity's bounds; ``at_limit=NAME:DOF,...`` fails the region unless each DOF of
that design's NLP posture is at a joint limit (what the prose says of them).
"""

from __future__ import annotations

from typing import Any

import numpy as np

import casadi_posture as cp
from casadi_posture.output.design_plots import SWEEP_POINTS
from casadi_posture.workplace_design import design, sweep
from casadi_posture.workplace_design.nlp import MAX_ITERATIONS
from casadi_posture.workplace_design.quantities import parse_free

from . import parallel
from .low_back import minus
from .regions import Region
from .session import ROOT, Session

#: A joint angle within this of a limit is at it [rad] (0.01°).
AT_LIMIT_RAD = 1.75e-4


def facts(path: str, free: str, objective: str, swept: bool) -> dict[str, Any]:
    """The design of the problem at ``path`` (the repository's) with ``free`` (``--free``'s
    values joined by ``;``) for ``objective``: what :func:`values` gives, and
    ``at_limit``, the DOFs of the NLP's posture at a joint limit."""
    problem = cp.load(ROOT / path)
    answer = design(problem, parse_free(free.split(";"), path), objective)
    body, q = problem.body, answer.best_answer.torques.q
    gap = np.minimum(np.abs(q - body.lower), np.abs(q - body.upper))
    posture = {name: float(np.degrees(q[j])) for name, j in body.index.items()}
    found: dict[str, Any] = {
        "start": answer.start.value,
        "best": answer.best.value,
        "check": answer.check.value,
        "start_m": tuple(f.start_m for f in answer.free),
        "best_m": answer.best_m,
        "gain": answer.gain,
        "ratio": answer.ratio,
        "iterations": answer.iterations,
        "max_iterations": MAX_ITERATIONS,
        "gap_deg": answer.posture_gap_deg,
        "posture": posture,
        "signed": {name: minus(value) for name, value in posture.items()},
        "at_limit": {name for name, j in body.index.items() if gap[j] <= AT_LIMIT_RAD},
    }
    if answer.best_answer.low_back is not None:
        found["moment_Nm"] = round(answer.best_answer.low_back.sagittal_moment, 1) + 0.0
    if swept:
        quantity = answer.free[0]
        grid = np.linspace(quantity.lower_m, quantity.upper_m, SWEEP_POINTS)
        kept = [(p.value_m, p.score.value) for p in sweep(answer, grid) if p.kept]
        found |= {"first": kept[0], "least": min(kept, key=lambda p: p[1]), "last": kept[-1]}
    return found


def values(region: Region, session: Session) -> dict[str, Any]:
    """Each named design's numbers (``NAME=``): ``start``, ``best`` (the NLP's) and
    ``check`` (the IK re-solved at the design) objective values [N or min], ``start_m`` and
    ``best_m`` the design [m], ``gain`` and ``ratio`` (as ``Design``), ``iterations``
    (IPOPT's), ``max_iterations`` (its limit), ``gap_deg`` the largest joint difference
    between the NLP's and the IK's postures, ``posture`` the NLP's posture [deg] by DOF
    (``signed``: as text with a typographic minus), ``moment_Nm`` its sagittal moment at
    L5/S1 (compression only), and for the design of ``sweep=``: ``first``, ``least`` and
    ``last``, the points (value [m], objective) of ``design.png``'s sweep where the IK
    keeps the task: the first, the one of least objective and the last. Raises
    ``ValueError`` when a DOF of ``at_limit=`` is not at a joint limit."""
    args = dict(region.args)
    path, swept = args.pop("problem"), args.pop("sweep", None)
    limited, _, dofs = args.pop("at_limit", "").partition(":")
    cases = {}
    for name, text in args.items():
        objective, _, free = text.partition(" ")
        cases[name] = (path, free, objective, name == swept)
    found = parallel.compute(facts, list(cases.values()))
    named = {name: found[case] for name, case in cases.items()}
    missing = [n for n in dofs.split(",") if n and n not in named[limited]["at_limit"]]
    if missing:
        raise ValueError(f"{', '.join(missing)} not at a joint limit: the prose says they are")
    return named
