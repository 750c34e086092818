"""A run's per-step measures, computed once and shared by its timeline, summary, figures
and row (each asks for them in turn)."""

from __future__ import annotations

import functools
import weakref
from collections.abc import Callable
from typing import Generic, TypeVar

from casadi_posture.simulation import SimulationResult

T = TypeVar("T")


class OncePerRun(Generic[T]):
    """``measure`` that keeps its value for the last run it was given (by weak reference:
    the run is not kept alive) and returns it again for that run."""

    def __init__(self, measure: Callable[[SimulationResult], T]) -> None:
        self.measure = measure
        self._last: tuple[weakref.ref[SimulationResult], T] | None = None
        functools.update_wrapper(self, measure)

    def __call__(self, result: SimulationResult) -> T:
        if self._last is not None and self._last[0]() is result:
            return self._last[1]
        return self.remember(result, self.measure(result))

    def remember(self, result: SimulationResult, value: T) -> T:
        """Keep ``value``, measured elsewhere (a process that sent ``result``), as
        ``result``'s."""
        self._last = (weakref.ref(result), value)
        return value


def once_per_run(measure: Callable[[SimulationResult], T]) -> OncePerRun[T]:
    """``measure`` computed once per run (``OncePerRun``)."""
    return OncePerRun(measure)
