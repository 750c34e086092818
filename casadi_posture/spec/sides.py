"""The side of a name: ``_r`` for the right, ``_l`` for the left (DOFs, segments, half-joints,
effectors); a name without either suffix is on neither side."""

from __future__ import annotations

from collections.abc import Iterable


def mirror_name(name: str | None) -> str | None:
    """``name`` with its side suffix swapped (``_r`` ↔ ``_l``); unchanged without one."""
    if name is None:
        return None
    for side, other in (("_r", "_l"), ("_l", "_r")):
        if name.endswith(side):
            return name[: -len(side)] + other
    return name


def sided_pairs(names: Iterable[str]) -> list[tuple[str, str]]:
    """(right, left) pairs among ``names``: each ``_r`` name whose mirror is there too."""
    given = set(names)
    return sorted(
        (name, other)
        for name in given
        if name.endswith("_r") and (other := mirror_name(name)) in given and other is not None
    )
