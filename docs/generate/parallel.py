"""Independent simulations of the generators, run on every core in fresh processes: a
generator's cases may be submitted before its region is reached (:func:`submit`), so that
they run while the documents before it are made."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Hashable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any

_pool: ProcessPoolExecutor | None = None
_futures: dict[tuple[str, tuple[Hashable, ...]], Future[Any]] = {}


def submit(function: Callable[..., Any], cases: Sequence[tuple[Hashable, ...]]) -> None:
    """Start ``function(*case)`` for every case not started yet (``function`` a
    module-level function whose result pickles), on ``os.cpu_count()`` processes."""
    global _pool
    if _pool is None:
        context = multiprocessing.get_context("spawn")
        _pool = ProcessPoolExecutor(os.cpu_count() or 1, mp_context=context)
    name = f"{function.__module__}.{function.__qualname__}"
    for case in cases:
        if (name, case) not in _futures:
            _futures[name, case] = _pool.submit(function, *case)


def compute(function: Callable[..., Any], cases: Sequence[tuple[Hashable, ...]]) -> dict[Any, Any]:
    """``{case: function(*case)}`` for every case, started now unless :func:`submit`
    started it."""
    submit(function, cases)
    name = f"{function.__module__}.{function.__qualname__}"
    return {case: _futures[name, case].result() for case in cases}


def shutdown() -> None:
    """Stop the processes and forget every result (a later run computes them again)."""
    global _pool
    if _pool is not None:
        _pool.shutdown(cancel_futures=True)
    _pool = None
    _futures.clear()
