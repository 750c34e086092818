"""Times on the command line: one grammar for every option that takes seconds.

A time is a number of seconds (``90``) or a number with a unit: ``s``, ``min`` or ``h``
(``90s``, ``1.5min``, ``8h``). Each command checks the range it needs (a rest ≥ 0, a
duration > 0) after reading it.
"""

from __future__ import annotations

import math
import re
from typing import Any

import click

#: The grammar in words, as every refusal states it (docs/commands.md says it once).
GRAMMAR = "a time in s, or with a unit s, min or h: 90, 90s, 1.5min, 8h"

#: Seconds per unit.
UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0}

_TIME = re.compile(r"\s*([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)\s*(s|min|h)?\s*")


def seconds(text: str) -> float:
    """``text`` in the grammar above as a finite number of seconds; ``ValueError`` (its
    message the grammar) for anything else: ``"8 hours"``, ``"inf"``, ``""``, ``1e999``."""
    match = _TIME.fullmatch(text)
    value = math.inf if match is None else float(match.group(1)) * UNITS[match.group(2) or "s"]
    if not math.isfinite(value):
        raise ValueError(GRAMMAR)
    return value


class Seconds(click.ParamType):
    """A click option's type: a time in the grammar above, as seconds [s] (``many``: a
    comma-separated list of them, as a tuple). A value outside the grammar is click's
    one-line usage error naming the option, the value and the grammar (exit code 2)."""

    name = "time"

    def __init__(self, *, many: bool = False) -> None:
        self.many = many

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        if isinstance(value, tuple):  # a default already converted
            return value
        try:
            if self.many:
                return tuple(seconds(part) for part in str(value).split(","))
            return seconds(str(value))
        except ValueError:
            listed = ", or a list of them: 0,30,1min" if self.many else ""
            self.fail(f"{value!r}: expected {GRAMMAR}{listed}", param, ctx)


#: One time [s] and a list of them, for ``click.option(type=...)``.
TIME = Seconds()
TIMES = Seconds(many=True)
