"""The generators by name, and how a region's text is made and compared."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from . import (
    arm_figures,
    comfort_runs,
    compression_sensitivity,
    console,
    design_text,
    duty_text,
    endurance,
    low_back,
    low_back_cases,
    paper_arm,
    plausibility_table,
    population,
    postures,
    python_output,
    recording,
    runs,
    scenarios_text,
    schema_tables,
    sensitivity,
    start_scores,
    strength,
    strength_history,
    wall,
)
from .regions import Region
from .session import Session


@dataclass(frozen=True)
class Generator:
    """``make(region, session)`` returns the region's text, or the values its template
    names; text matching ``volatile`` (timings) is not compared."""

    make: Callable[[Region, Session], str | Mapping[str, Any]]
    volatile: re.Pattern[str] | None = None
    prefetch: Callable[[], None] | None = None


GENERATORS: dict[str, Generator] = {
    "console": Generator(console.generate, console.TIMINGS),
    "python-output": Generator(python_output.generate),
    "arm-figures": Generator(arm_figures.values, prefetch=arm_figures.prefetch),
    "holding-laws": Generator(paper_arm.laws_table, prefetch=paper_arm.prefetch),
    "paper-arm": Generator(paper_arm.values, prefetch=paper_arm.prefetch),
    "wall-table": Generator(wall.table, prefetch=wall.prefetch),
    "wall-example": Generator(wall.example_table, prefetch=wall.prefetch),
    "wall": Generator(wall.values, prefetch=wall.prefetch),
    "scenarios": Generator(scenarios_text.values, prefetch=scenarios_text.prefetch),
    "endurance-table": Generator(endurance.table),
    "endurance": Generator(endurance.values),
    "recovery-laws": Generator(endurance.laws, prefetch=endurance.prefetch_laws),
    "low-back-cases": Generator(low_back_cases.values),
    "compression-sensitivity": Generator(compression_sensitivity.values),
    "design": Generator(design_text.values),
    "duty-cycle": Generator(duty_text.values),
    "low-back": Generator(low_back.values, prefetch=low_back.prefetch),
    "posture": Generator(postures.values),
    "strength-age": Generator(strength.values),
    "strengths": Generator(strength.strengths),
    "recording": Generator(recording.values, prefetch=recording.prefetch),
    "population": Generator(population.block, prefetch=population.prefetch),
    "population-facts": Generator(population.facts, prefetch=population.prefetch),
    "ansur-table": Generator(population.ansur_table),
    "ansur": Generator(population.ansur),
    "sensitivity-inputs": Generator(sensitivity.values),
    "schema": Generator(schema_tables.values),
    "summary": Generator(runs.summary),
    "simulate": Generator(runs.simulate),
    "solve": Generator(runs.solve),
    "table": Generator(runs.table),
    "strength-flexors": Generator(strength_history.flexors, prefetch=strength_history.prefetch),
    "strength-rotators": Generator(strength_history.rotators, prefetch=strength_history.prefetch),
    "comfort-adjustments": Generator(comfort_runs.adjustments, prefetch=comfort_runs.prefetch),
    "comfort-free-wall": Generator(comfort_runs.free_wall, prefetch=comfort_runs.prefetch),
    "comfort-data": Generator(comfort_runs.data),
    "comfort-wall": Generator(comfort_runs.wall_recoveries, prefetch=wall.prefetch),
    "plausibility-data": Generator(plausibility_table.thresholds),
    "plausibility-runs": Generator(plausibility_table.values, prefetch=plausibility_table.prefetch),
    "start-scores": Generator(start_scores.table),
    "run-scores": Generator(start_scores.run_scores),
}


def render(region: Region, session: Session) -> str:
    """The region's text as its generator makes it today (ending with a newline)."""
    made = GENERATORS[region.name].make(region, session)
    if region.template is not None:
        if isinstance(made, str):
            raise TypeError(f"generator {region.name!r} writes text, not a template's values")
        made = region.template.format_map(made)
    elif not isinstance(made, str):
        raise TypeError(f"generator {region.name!r} gives values: its marker needs a template")
    return made.rstrip("\n") + "\n"


def same(region: Region, text: str) -> bool:
    """Whether ``text`` says what the region says, timings aside."""
    volatile = GENERATORS[region.name].volatile
    if volatile is None:
        return text == region.body
    return volatile.sub("<timing>", text) == volatile.sub("<timing>", region.body)
