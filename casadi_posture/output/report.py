"""Plain-text tables for the terminal, aligned, with units in the headers."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

#: The columns of a static answer's half-joint table (``StaticAnswer.half_joints``, in that
#: order) and of its DOF table (``StaticAnswer.dofs``), with units.
HALF_JOINT_COLUMNS = (
    "half-joint", "DOF", "strength (N·m)", "torque (N·m)", "load (%MVC)", "endurance (min)",
    "verdict",
)  # fmt: skip
DOF_COLUMNS = ("DOF", "angle (deg)", "external (N·m)", "passive (N·m)", "active (N·m)")


def fmt(value: Any, digits: int = 3) -> str:
    """A cell: floats with fixed decimals, an unlimited value (infinity) as '∞', None as '-'.
    A nan, which no answer may carry, shows as 'nan' so that it cannot hide."""
    if value is None:
        return "-"
    if isinstance(value, float):
        if math.isinf(value):
            return "∞" if value > 0 else "-∞"
        text = f"{value:.{digits}f}"
        return text[1:] if text.startswith("-") and float(text) == 0.0 else text
    return str(value)


def table(
    headers: Sequence[str],
    rows: Sequence[Sequence[Any]],
    digits: int = 3,
    right: set[int] | None = None,
) -> str:
    """Columns padded to their widest cell; text left-aligned, numbers (and the columns
    listed in ``right``) right-aligned."""
    cells = [[fmt(v, digits) for v in row] for row in rows]
    numeric = [
        i in (right or set())
        or all(isinstance(row[i], (int, float)) or row[i] is None for row in rows)
        for i in range(len(headers))
    ]
    widths = [max([len(h)] + [len(r[i]) for r in cells]) for i, h in enumerate(headers)]

    def line(values: Sequence[str]) -> str:
        parts = [
            v.rjust(w) if num else v.ljust(w)
            for v, w, num in zip(values, widths, numeric, strict=True)
        ]
        return "  ".join(parts).rstrip()

    return "\n".join([line(headers), line(["-" * w for w in widths]), *map(line, cells)])
