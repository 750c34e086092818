"""A run's per-step measures, computed once and shared by its timeline, summary, figures
and row (each asks for them in turn)."""

from __future__ import annotations

import functools
import weakref
from collections.abc import Callable
from typing import TypeVar

from casadi_posture.simulation import SimulationResult

T = TypeVar("T")


def once_per_run(measure: Callable[[SimulationResult], T]) -> Callable[[SimulationResult], T]:
    """``measure`` that keeps its value for the last run it was given (by weak reference:
    the run is not kept alive) and returns it again for that run."""
    last: tuple[weakref.ref[SimulationResult], T] | None = None

    @functools.wraps(measure)
    def cached(result: SimulationResult) -> T:
        nonlocal last
        if last is not None and last[0]() is result:
            return last[1]
        value = measure(result)
        last = (weakref.ref(result), value)
        return value

    return cached
