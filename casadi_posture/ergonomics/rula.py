"""The RULA worksheet (McAtamney & Corlett 1993, Applied Ergonomics 24:91-99) as pure
functions: the step scores of one side's posture, the posture scores from Tables A and B,
scores C and D with muscle use and force, the grand score from Table C and its action
level. Tables, bands and their sources: ``data/rula_reba.toml``, docs/rula_reba.md."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from functools import cache
from typing import Any

from casadi_posture.data import parameters


@cache
def value(name: str) -> Any:
    """The worksheet record ``name`` of ``data/rula_reba.toml`` (its ``value``; not to be
    changed in place: every worksheet shares it)."""
    return parameters.load("rula_reba")[f"rula_reba.{name}"].value


def band(x: float, prefix: str, edges: str = "edges", on_edge: str = "on_edge") -> int:
    """The score of ``x`` in the band table ``prefix`` (edges, scores, on_edge): an ``x``
    beyond the outermost edges takes the outermost interval's score."""
    cuts, sides = value(f"{prefix}.{edges}"), value(f"{prefix}.{on_edge}")
    return int(value(f"{prefix}.scores")[interval(x, cuts, sides)])


def interval(x: float, cuts: Sequence[float], sides: Sequence[str]) -> int:
    """The index of the interval of ``x`` among ``cuts`` (an edge goes ``below``/``above``)."""
    for i, (cut, side) in enumerate(zip(cuts, sides, strict=True)):
        if x < cut or (x == cut and side == "below"):
            return i
    return len(cuts)


def clip(score: int, low: int, high: int) -> int:
    """``score`` kept within a table's rows ``low``..``high``."""
    return max(low, min(high, score))


def check_finite(inputs: object) -> None:
    """Refuse a non-finite or negative-load field of a worksheet's inputs."""
    for name in _numbers(type(inputs)):
        v = getattr(inputs, name)
        if isinstance(v, float | int) and not isinstance(v, bool):
            if not math.isfinite(v):
                raise ValueError(f"{name} = {v}: a finite number is needed")
            if name.endswith("_kg") and v < 0:
                raise ValueError(f"{name} = {v}: a load >= 0 kg is needed")


@cache
def _numbers(kind: type) -> tuple[str, ...]:
    """The fields of a worksheet's inputs that hold numbers (not flags)."""
    return tuple(f.name for f in fields(kind) if f.type in ("float", "int", float, int))


@dataclass(frozen=True)
class RulaInputs:
    """One side's posture and task for RULA. Angles [deg]: upper arm flexion (+) or
    extension (−) from the trunk; elbow flexion (0 = straight); wrist flexion (+) or
    extension (−); neck flexion (+) or extension (−) from the trunk; trunk flexion (+) or
    extension (−) from the vertical. ``load_kg`` [kg] is the load or force handled."""

    upper_arm_deg: float
    lower_arm_deg: float
    wrist_deg: float = 0.0
    shoulder_raised: bool = False
    arm_abducted: bool = False
    arm_supported: bool = False
    arm_across_or_out: bool = False
    wrist_deviated: bool = False
    wrist_twist_at_end: bool = False
    neck_deg: float = 0.0
    neck_twisted: bool = False
    neck_side_bent: bool = False
    trunk_deg: float = 0.0
    trunk_supported_seated: bool = False
    trunk_twisted: bool = False
    trunk_side_bent: bool = False
    legs_supported: bool = True
    static_or_repeated: bool = False
    load_kg: float = 0.0
    load_static_or_repeated: bool = False
    shock: bool = False

    def __post_init__(self) -> None:
        check_finite(self)


@dataclass(frozen=True)
class RulaResult:
    """Every score of the worksheet, the grand score (1-7), its action level (1-4) and the
    action the paper names."""

    upper_arm: int
    lower_arm: int
    wrist: int
    wrist_twist: int
    posture_a: int
    muscle_use: int
    force: int
    score_c: int
    neck: int
    trunk: int
    legs: int
    posture_b: int
    score_d: int
    grand: int
    action_level: int
    action: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def upper_arm(x: RulaInputs) -> int:
    """Step 1: the band of the upper arm's angle, +1 raised, +1 abducted, −1 supported."""
    score = band(x.upper_arm_deg, "rula.upper_arm")
    score += int(x.shoulder_raised) + int(x.arm_abducted) - int(x.arm_supported)
    return clip(score, 1, 6)


def lower_arm(x: RulaInputs) -> int:
    """Step 2: the band of the elbow's flexion, +1 across the midline or out to the side."""
    return clip(band(x.lower_arm_deg, "rula.lower_arm") + int(x.arm_across_or_out), 1, 3)


def wrist(x: RulaInputs) -> int:
    """Step 3: neutral 1, else the band of the flexion's or extension's size; +1 deviated."""
    size = abs(x.wrist_deg)
    score = 1 if size <= value("neutral_tolerance") else band(size, "rula.wrist")
    return clip(score + int(x.wrist_deviated), 1, 4)


def wrist_twist(x: RulaInputs) -> int:
    """Step 4: 1 in the mid-range of twist, 2 at or near its end."""
    return int(value("rula.wrist_twist")[int(x.wrist_twist_at_end)])


def neck(x: RulaInputs) -> int:
    """Step 9: the band of the neck's flexion, 4 in extension; +1 twisted, +1 side-bent."""
    if x.neck_deg < -value("neutral_tolerance"):
        score = int(value("rula.neck.extension"))
    else:
        score = band(max(x.neck_deg, 0.0), "rula.neck")
    return clip(score + int(x.neck_twisted) + int(x.neck_side_bent), 1, 6)


def trunk(x: RulaInputs) -> int:
    """Step 10: 1 upright (or well supported seated), else the band of the trunk's angle
    from the vertical (its size when extended); +1 twisted, +1 side-bent."""
    size = abs(x.trunk_deg)
    if x.trunk_supported_seated or size <= value("neutral_tolerance"):
        score = int(value("rula.trunk.upright"))
    else:
        score = band(size, "rula.trunk")
    return clip(score + int(x.trunk_twisted) + int(x.trunk_side_bent), 1, 6)


def legs(x: RulaInputs) -> int:
    """Step 11: 1 supported and balanced, 2 if not."""
    return int(value("rula.legs")[0 if x.legs_supported else 1])


def muscle_use(x: RulaInputs) -> int:
    """Steps 6 and 13: +1 mainly static (held > 1 min) or repeated ≥ 4 times a minute."""
    return int(value("rula.muscle_use")) if x.static_or_repeated else 0


def force(x: RulaInputs) -> int:
    """Steps 7 and 14: the load's band, by whether it is held statically or repeated;
    3 for a shock or a rapid build-up of force."""
    if x.shock:
        return int(value("rula.force.shock"))
    kind = "static_or_repeated" if x.load_static_or_repeated else "intermittent"
    i = interval(x.load_kg, value("rula.force.edges_kg"), value("rula.force.on_edge"))
    return int(value(f"rula.force.{kind}")[i])


def action_level(grand: int) -> tuple[int, str]:
    """The action level (1-4) of a grand score and the paper's words for it."""
    uppers, actions = value("rula.action_levels.upper_scores"), value("rula.action_levels.actions")
    level = next((i for i, top in enumerate(uppers) if grand <= top), len(uppers) - 1)
    return level + 1, str(actions[level])


def score(x: RulaInputs) -> RulaResult:
    """The whole worksheet for one side: every intermediate score and the grand score."""
    ua, la, wr, tw = upper_arm(x), lower_arm(x), wrist(x), wrist_twist(x)
    posture_a = int(value("rula.table_a")[ua - 1][la - 1][wr - 1][tw - 1])
    nk, tr, lg = neck(x), trunk(x), legs(x)
    posture_b = int(value("rula.table_b")[nk - 1][tr - 1][lg - 1])
    muscle, load = muscle_use(x), force(x)
    score_c, score_d = posture_a + muscle + load, posture_b + muscle + load
    table_c = value("rula.table_c")
    grand = int(table_c[min(score_c, len(table_c)) - 1][min(score_d, len(table_c[0])) - 1])
    level, action = action_level(grand)
    return RulaResult(
        ua, la, wr, tw, posture_a, muscle, load, score_c, nk, tr, lg, posture_b, score_d, grand,
        level, action,
    )  # fmt: skip
