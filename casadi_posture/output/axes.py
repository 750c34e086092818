"""The axes of a what-if grid: one problem key, or keys tied to one value (``KEY1,KEY2``:
both hands' heights, both halves of a load), and their names in words for figures."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from casadi_posture.errors import ProblemError
from casadi_posture.problem import KEY_UNITS
from casadi_posture.spec.overrides import parse_key

#: The varied IK solver: an axis of its own, not a problem key.
SOLVER = "solver"
#: A world position's coordinates in words (x forward, y to the subject's left, z up).
POSITION_WORDS = ("distance forward", "distance to the left", "height")
#: Key names that read poorly with their underscores replaced by spaces.
NAMES = {
    SOLVER: "IK solver",
    "r_min": "R_min",
    "strategy": "recovery strategy",
    "recovery_law": "recovery law",
}


def axis_keys(axis: str, problem: Any = None) -> list[str]:
    """The problem keys ``axis`` sets (``KEY1,KEY2`` ties them to one value), each a
    dotted key, each once, ``solver`` alone; ``problem`` names the file in the one-line
    ``ProblemError`` otherwise."""
    keys = [key.strip() for key in axis.split(",")]
    expected = "KEY or KEY1,KEY2 (keys tied to one value), such as loads[0].mass_kg"
    for key in keys:
        if not key:
            raise ProblemError(problem, "--vary", axis, expected)
        if key == SOLVER and len(keys) > 1:
            raise ProblemError(problem, "--vary", axis, "solver varied on its own")
        if key != SOLVER:
            try:
                parse_key(key)
            except ProblemError as error:
                raise ProblemError(problem, "--vary", key, error.expected) from None
    if len(set(keys)) != len(keys):
        raise ProblemError(problem, "--vary", axis, "each key tied once")
    return keys


def check_units(keys: Sequence[str], problem: Any = None) -> None:
    """Tied keys must carry one unit (``target_m`` and ``stature_m``, not ``mass_kg``)."""
    units = {key: unit(key) or "no unit" for key in keys}
    if len(set(units.values())) > 1:
        shown = ", ".join(f"{key} in {u}" for key, u in units.items())
        raise ProblemError(problem, f"--vary {','.join(keys)}", shown, "tied keys of one unit")


def unit(key: str) -> str:
    """The unit a key's name carries (``tasks[2].target_m[2]`` -> ``m``), or ''."""
    suffix = _suffix(key.rsplit(".", 1)[-1].split("[", 1)[0])
    return KEY_UNITS[suffix].split("(")[0].strip() if suffix else ""


def _suffix(name: str) -> str:
    """The unit suffix of a key name (``mass_kg`` -> ``_kg``), or ''."""
    return next((suffix for suffix in KEY_UNITS if name.endswith(suffix)), "")


def axis_value(row: Mapping[str, Any], axis: str) -> Any:
    """A case's value on ``axis``: its solver, or its first tied key's value."""
    return row.get(SOLVER) if axis == SOLVER else row.get(axis.split(",")[0].strip())


def axis_label(data: Mapping[str, Any], axis: str) -> tuple[str, str]:
    """``axis`` in words and its unit, from the problem's ``data`` (the names of its tasks
    and loads): ``tasks[2].target_m[2],tasks[3].target_m[2]`` -> ('right/left hand at
    shelf height', 'm')."""
    keys = axis_keys(axis)
    owners, fields = zip(*(_words(data, key) for key in keys), strict=True)
    if len(set(fields)) == 1:
        words = " ".join(w for w in (_merged(owners), fields[0]) if w)
    else:
        pairs = zip(owners, fields, strict=True)
        words = ", ".join(" ".join(w for w in pair if w) for pair in pairs)
    return words, unit(keys[0])


def with_unit(words: str, unit_name: str) -> str:
    """An axis title: ``height (m)``."""
    return f"{words} ({unit_name})" if unit_name else words


def _words(data: Mapping[str, Any], key: str) -> tuple[str, str]:
    """(the named item a key belongs to, the quantity) in words: ``tasks[2].target_m[2]``
    -> ('right hand at shelf', 'height'); ``body.stature_m`` -> ('body', 'stature')."""
    if key == SOLVER:
        return "", NAMES[SOLVER]
    parts = parse_key(key)
    owner = ""
    if len(parts) > 2 and isinstance(parts[0], str) and isinstance(parts[1], int):
        items = data.get(parts[0])
        item = items[parts[1]] if isinstance(items, list) and parts[1] < len(items) else None
        name = item.get("name") if isinstance(item, dict) else None
        owner = str(name or f"{parts[0]} {parts[1]}").replace("_", " ")
        parts = parts[2:]
    elif parts[0] == "body":
        owner = "body"
    names = [p for p in parts if isinstance(p, str)]
    field = names[-1] if names else str(parts[-1])
    stem = field.removesuffix(_suffix(field))
    stem = NAMES.get(stem, stem.replace("_", " "))
    index = parts[-1] if isinstance(parts[-1], int) else None
    if index is None:
        return owner, stem
    if _suffix(field) == "_m" and index < len(POSITION_WORDS):
        coordinate = POSITION_WORDS[index]
        return owner, coordinate if stem == "target" else f"{stem} {coordinate}"
    return owner, f"{stem} {'xyz'[index] if index < 3 else index}"


def _merged(names: Sequence[str]) -> str:
    """Names that differ in a word or two, merged: 'right hand at shelf' and 'left hand at
    shelf' -> 'right/left hand at shelf'."""
    if len(set(names)) == 1:
        return names[0]
    words = [name.split() for name in names]
    shortest = min(len(w) for w in words)
    head = 0
    while head < shortest and len({w[head] for w in words}) == 1:
        head += 1
    tail = 0
    while tail < shortest - head and len({w[-1 - tail] for w in words}) == 1:
        tail += 1
    middles = [" ".join(w[head : len(w) - tail]) for w in words]
    if not all(middles):
        return "/".join(names)
    return " ".join([*words[0][:head], "/".join(middles), *words[0][len(words[0]) - tail :]])
