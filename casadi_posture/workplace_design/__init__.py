"""Workplace design by gradients: the task's target coordinates (a shelf's height, a line's
position) chosen within bounds to maximise the task's static endurance or the share of a
population capable of it, or to minimise the low-back compression, by one NLP over the
posture and the design together (docs/design.md).

- ``quantities``: the free quantities (``--free KEY=LO:HI``, tied keys, bounds) and their
  places in the hierarchy's target vector;
- ``objectives``: the objectives, an answer's score on each, and how two scores compare;
- ``nlp``: the design NLP (its variables, constraints and each objective's measures), its
  cache, the independent rows of the kept levels, the endurance threshold's check;
- ``answer``: the ``Design`` answer and the sweep over one free quantity;
- ``solve``: ``design``, the entry point, and the re-solve check of its answer.
"""

from __future__ import annotations

from casadi_posture.workplace_design.answer import BOUND_TOLERANCE_M, Design, SweepPoint, sweep
from casadi_posture.workplace_design.nlp import (
    CACHED_STRUCTURES,
    MAX_ITERATIONS,
    design_nlp,
    independent_rows,
)
from casadi_posture.workplace_design.objectives import (
    CHECK_RELATIVE,
    CHECK_SHARE_PCT,
    COMPRESSION_UNIT,
    OBJECTIVES,
    Score,
    score,
)
from casadi_posture.workplace_design.quantities import Free, free_quantities, parse_free
from casadi_posture.workplace_design.solve import CLAMP_MARGIN_PCT_MVC, design, spread

__all__ = [
    "BOUND_TOLERANCE_M",
    "CACHED_STRUCTURES",
    "CHECK_RELATIVE",
    "CHECK_SHARE_PCT",
    "CLAMP_MARGIN_PCT_MVC",
    "COMPRESSION_UNIT",
    "MAX_ITERATIONS",
    "OBJECTIVES",
    "Design",
    "Free",
    "Score",
    "SweepPoint",
    "design",
    "design_nlp",
    "free_quantities",
    "independent_rows",
    "parse_free",
    "score",
    "spread",
    "sweep",
]
