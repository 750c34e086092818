"""Changes to a problem file given as dotted keys: ``fatigue.strategy``, ``loads[0].mass_kg``.

Command-line options, what-if grids and batch cases use them; the changed file is then
validated like any other, so a bad value gets the same one-line error.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Mapping
from copy import deepcopy
from pathlib import Path
from typing import Any

from casadi_posture.errors import MISSING, ProblemError

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]")


def parse_key(key: str) -> list[str | int]:
    """``loads[0].mass_kg`` -> ['loads', 0, 'mass_kg'] (``loads.0.mass_kg`` works too)."""
    parts: list[str | int] = []
    for piece in key.split("."):
        if piece.isdigit():
            parts.append(int(piece))
            continue
        matched = 0
        for match in _TOKEN.finditer(piece):
            if match.start() != matched:
                break
            parts.append(match.group(1) if match.group(1) else int(match.group(2)))
            matched = match.end()
        if matched != len(piece) or not piece:
            raise ProblemError(
                None, key, None, "a dotted key such as fatigue.r_min or loads[0].mass_kg"
            )
    return parts


def split_assignment(text: str, option: str, path: Any, example: str) -> tuple[str, str]:
    """``KEY=VALUE`` -> (key, value text), the key checked; a malformed one is a
    ``ProblemError`` naming the command-line ``option`` and an ``example``."""
    key, sep, value = text.partition("=")
    if not sep or not key or not value:
        raise ProblemError(path, option, text, example)
    try:
        parse_key(key)
    except ProblemError as error:
        raise ProblemError(path, option, text, error.expected) from None
    return key, value


def parse_value(text: str, path: Any = None, key: str = "--set") -> Any:
    """A value as TOML reads it (``5``, ``2.5``, ``true``, ``[0, 1]``); otherwise the string.
    Arrays or tables nested deeper than ``MAX_NESTING`` are a ``ProblemError`` naming ``key``
    (the option) and ``path`` (the problem file)."""
    try:
        value = tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text
    except RecursionError:
        raise ProblemError(
            path, key, text, "a value with arrays or tables less deeply nested"
        ) from None
    check_nesting(value, path, key)
    return value


#: Tables and arrays nested deeper than this are refused before validation.
MAX_NESTING = 16


def check_nesting(raw: Any, path: Any, key: str = "") -> None:
    """Refuse data nested deeper than ``MAX_NESTING``, naming the deepest key below ``key``
    (iteratively: no recursion to exhaust)."""
    stack = [(raw, 0, key)]
    while stack:
        node, depth, key = stack.pop()
        if depth > MAX_NESTING:
            expected = f"tables and arrays nested at most {MAX_NESTING} deep"
            raise ProblemError(path, key or None, MISSING, expected)
        items = (
            node.items()
            if isinstance(node, dict)
            else enumerate(node)
            if isinstance(node, list)
            else ()
        )
        for name, child in items:
            part = f"[{name}]" if isinstance(name, int) else (f".{name}" if key else name)
            stack.append((child, depth + 1, key + part))


#: The keys that set a muscle group's strength, one at a time: an override of one of them
#: replaces whichever the file gives (a what-if over ``strength_Nm`` on a file that sets
#: ``strength_ratio``).
STRENGTH_KEYS = ("strength_Nm", "strength_curve", "strength_scale", "strength_ratio")


def apply(raw: dict[str, Any], overrides: Mapping[str, Any], path: Path | None) -> dict[str, Any]:
    """A copy of the file's data ``raw`` with each dotted key set to its value; setting one
    of a group's ``STRENGTH_KEYS`` drops the file's others (not those set alongside)."""
    if not isinstance(overrides, Mapping):
        raise ProblemError(path, "overrides", overrides, "a mapping of dotted keys to values")
    out = deepcopy(raw)
    parsed = {key: parse_key(key) for key in overrides}
    for key, value in overrides.items():
        parts = parsed[key]
        node: Any = out
        for depth, part in enumerate(parts[:-1]):
            nxt = parts[depth + 1]
            if isinstance(part, int):
                if not isinstance(node, list) or part >= len(node):
                    raise ProblemError(path, key, value, "an index of an existing list item")
                node = node[part]
            else:
                if not isinstance(node, dict):
                    raise ProblemError(path, key, value, "a key inside a table")
                node = node.setdefault(part, [] if isinstance(nxt, int) else {})
        last = parts[-1]
        if isinstance(last, int):
            if not isinstance(node, list) or last >= len(node):
                raise ProblemError(path, key, value, "an index of an existing list item")
        elif not isinstance(node, dict):
            raise ProblemError(path, key, value, "a key inside a table")
        if last in STRENGTH_KEYS:
            given = {other[-1] for other in parsed.values() if other[:-1] == parts[:-1]}
            for other in set(STRENGTH_KEYS) - given:
                node.pop(other, None)
        node[last] = value
    return out


def changes(overrides: Mapping[str, Any], most: int | None = None) -> str:
    """Dotted-key overrides in words, ``loads[0].mass_kg = 6, fatigue.strategy = passive``
    (numbers to 6 significant digits); with ``most``, the first ``most`` of them and
    ``and N more``; empty without overrides."""
    shown = [
        f"{key} = {value:g}" if isinstance(value, float) else f"{key} = {value}"
        for key, value in overrides.items()
    ]
    if most is not None and len(shown) > most:
        shown = [*shown[:most], f"and {len(shown) - most} more"]
    return ", ".join(shown)
