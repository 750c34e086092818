"""Ctrl-C that stops a long run cleanly, between two steps or two cases.

IPOPT, through CasADi, catches SIGINT while it solves and carries on, so Python's
default ``KeyboardInterrupt`` is lost. Inside ``deferred`` a Ctrl-C only sets a
flag, which the time loop and the batch loop read between steps (``requested``):
a run stops within one step, keeps what it has, and says it was interrupted. A second
Ctrl-C raises ``KeyboardInterrupt`` at once wherever Python code runs.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

#: Exit code of a command stopped by Ctrl-C (128 + SIGINT, as shells report it).
EXIT_CODE = 130

_requested = threading.Event()
_depth = 0


def _handler(signum: int, frame: object) -> None:
    if _requested.is_set():
        raise KeyboardInterrupt
    _requested.set()


@contextmanager
def deferred() -> Iterator[None]:
    """Turn Ctrl-C into a request while the block runs (main thread only; nests)."""
    global _depth
    ignored = signal.getsignal(signal.SIGINT) == signal.SIG_IGN
    if threading.current_thread() is not threading.main_thread() or ignored:
        yield  # a worker thread, or a process told to ignore Ctrl-C (a background job)
        return
    if _depth == 0:
        _requested.clear()
        previous = signal.signal(signal.SIGINT, _handler)
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1
        if _depth == 0:
            signal.signal(signal.SIGINT, previous)


def requested() -> bool:
    """Whether Ctrl-C was pressed inside the current ``deferred`` block."""
    return _requested.is_set()


def ignore_in_worker() -> None:
    """Worker processes ignore Ctrl-C: the terminal sends it to the whole process group,
    and the parent decides what stops."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
