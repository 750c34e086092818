"""The inputs a sensitivity analysis differentiates with respect to, counted per problem
(``sensitivity-inputs problems=STEM,...``), for the prose that quotes how many."""

from __future__ import annotations

from typing import Any

import casadi_posture as cp
from casadi_posture.sensitivity_analysis.analysis import sensitivity

from .regions import Region
from .session import Session


def values(region: Region, session: Session) -> dict[str, Any]:
    """``inputs[STEM]``: the number of inputs of each problem of ``problems=``, ``dofs[STEM]``
    its body's DOFs, and ``fewest`` and ``most`` inputs among them."""
    stems = region.args["problems"].split(",")
    problems = {s: cp.load(session.folder / "problems" / f"{s}.toml") for s in stems}
    inputs = {s: len(sensitivity(p).inputs) for s, p in problems.items()}
    return {
        "inputs": inputs,
        "dofs": {s: p.body.n for s, p in problems.items()},
        "fewest": min(inputs.values()),
        "most": max(inputs.values()),
    }
