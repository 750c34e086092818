"""Independent simulations of a generator run on every core, in fresh processes."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Hashable, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any


def compute(function: Callable[..., Any], cases: Sequence[tuple[Hashable, ...]]) -> dict[Any, Any]:
    """``{case: function(*case)}`` for every case, on ``os.cpu_count()`` processes
    (``function`` a module-level function whose result pickles)."""
    workers = min(len(cases), os.cpu_count() or 1)
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(workers, mp_context=context) as pool:
        return dict(zip(cases, pool.map(function, *zip(*cases, strict=True)), strict=True))
