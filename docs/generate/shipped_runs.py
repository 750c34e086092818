"""The shipped 3-D problems simulated as shipped and under named variants (docs/comfort.md,
docs/strength.md, docs/plausibility.md), every run started in the background; a run the
wall or low-back generators make anyway (the same problem, the same keys) is theirs."""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import casadi_posture as cp

from . import low_back, parallel, strength, wall
from .session import ROOT

#: The shipped 3-D problems by the names the templates use.
STEMS = {
    "wall": "standing_wall_horizontal",
    "m25": "standing_wall_m25",
    "m45": "standing_wall_m45",
    "shelf": "standing_shelf_box",
    "drill": "standing_overhead_drill",
    "seated": "seated_assembly",
}
#: The wall lines' names in the wall generator, by stem.
WALL = {stem: line for line, stem in wall.LINES.items()}
#: The paper's adjustment with the constraint alone (the default keep_levels).
PAPER = {"fatigue.adjustment": "paper", "fatigue.strategy": "active", "fatigue.keep_levels": 0}
#: The groups whose measured strengths replaced the comfort measure's constants: the
#: shoulder flexors (the curve) and the rotators and trunk extensors (the measured values).
FLEXORS = ("shoulder_flexors",)
ROTATORS_AND_TRUNK = (
    "shoulder_internal_rotators",
    "shoulder_external_rotators",
    "lumbar_extensors",
)
#: Tasks a variant removes, by variant.
DROPPED = {"free_wall": ("sagittal_plane",)}


def earlier(groups: tuple[str, ...], stem: str) -> dict[str, Any]:
    """The keys that give ``groups`` (both sides where the body has two) their earlier
    constant strength, :func:`comfort_ratio` × the body's elbow flexion."""
    names = [h.name for h in cp.load(ROOT / "problems" / f"{stem}.toml").body.half_joints]
    return {
        f"body.half_joints.{name}.strength_ratio": strength.comfort_ratio(group)
        for group in groups
        for name in names
        if name in (group, f"{group}_r", f"{group}_l")
    }


#: The variants by name: the keys each sets on a problem (given its stem).
VARIANTS: dict[str, Callable[[str], dict[str, Any]]] = {
    "shipped": lambda stem: {},
    "paper": lambda stem: dict(PAPER),
    "whole_body": lambda stem: {"fatigue.adjustment": "whole_body"},
    "free_wall": lambda stem: dict(PAPER),
    "constant_flexors": lambda stem: earlier(FLEXORS, stem),
    "earlier_strengths": lambda stem: earlier(ROTATORS_AND_TRUNK, stem),
}


def problem(name: str, variant: str) -> cp.Problem:
    """The shipped problem ``name`` under ``variant``."""
    stem = STEMS[name]
    base = cp.load(ROOT / "problems" / f"{stem}.toml")
    data = copy.deepcopy(base.data)
    dropped = DROPPED.get(variant, ())
    data["tasks"] = [t for t in data["tasks"] if t["name"] not in dropped]
    return cp.from_dict(data, str(base.path), VARIANTS[variant](stem))


def simulate(name: str, variant: str) -> dict[str, Any]:
    """The summary of the problem ``name`` simulated under ``variant``, with ``extremes``:
    each DOF's least and largest angle over the run [deg] (``min``, ``max``, by DOF)."""
    run = cp.simulate(problem(name, variant))
    frame = run.to_frame()
    dofs = run.result.problem.body.dof_names
    return run.summary() | {
        "extremes": {
            d: {"min": frame[f"{d}_deg"].min(), "max": frame[f"{d}_deg"].max()} for d in dofs
        }
    }


def shared(name: str, variant: str) -> tuple[Callable[..., Any], tuple[Any, ...]]:
    """The function and case that make a run: the wall or low-back generator's when they
    make the same run, else :func:`simulate`."""
    stem = STEMS[name]
    if stem in WALL and variant in ("shipped", "whole_body"):
        return wall.run_facts, (WALL[stem], "whole")
    if stem in WALL and variant == "paper":
        return wall.run_facts, (WALL[stem], "paper0")
    if variant == "shipped":
        return low_back.run_summary, (stem,)
    return simulate, (name, variant)


def prefetch(cases: list[tuple[str, str]]) -> None:
    """Start the runs ``cases`` (problem name, variant) in the background."""
    for name, variant in cases:
        function, case = shared(name, variant)
        parallel.submit(function, [case])


def summary(name: str, variant: str) -> dict[str, Any]:
    """The summary of the problem ``name`` run under ``variant`` (once per check)."""
    function, case = shared(name, variant)
    return parallel.compute(function, [case])[case]


def start(name: str, variant: str = "shipped") -> cp.StaticAnswer:
    """The problem's start posture solved (the posture its runs start from)."""
    return cp.solve(problem(name, variant))
