"""Independent simulations of the generators, run on every core in fresh processes: a
generator's cases may be submitted before its region is reached (:func:`submit`), so that
they run while the documents before it are made. Each case runs once per check."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Hashable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
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
    """``{case: function(*case)}`` for every case; a case :func:`submit` did not start is
    started now on the processes when they are idle, else run here, and a case still
    queued is taken back and run here: this process waits only for the cases being run."""
    name = f"{function.__module__}.{function.__qualname__}"
    if any(not future.done() for future in _futures.values()):
        for case in cases:
            if (name, case) not in _futures:
                _futures[name, case] = here(function, case)
    submit(function, cases)
    while waiting := [c for c in cases if not _futures[name, c].done()]:
        queued = next((c for c in reversed(waiting) if _futures[name, c].cancel()), None)
        if queued is not None:  # not started yet: run here instead of waiting for a process
            _futures[name, queued] = here(function, queued)
        else:
            wait([_futures[name, c] for c in waiting], return_when=FIRST_COMPLETED)
    return {case: _futures[name, case].result() for case in cases}


def here(function: Callable[..., Any], case: tuple[Hashable, ...]) -> Future[Any]:
    """``function(*case)`` run in this process, as a finished future (its result, or the
    exception it raised)."""
    future: Future[Any] = Future()
    try:
        future.set_result(function(*case))
    except Exception as error:  # given back by result(), as a process's would be
        future.set_exception(error)
    return future


def shutdown() -> None:
    """Stop the processes and forget every result (a later run computes them again)."""
    global _pool
    if _pool is not None:
        _pool.shutdown(cancel_futures=True)
    _pool = None
    _futures.clear()
