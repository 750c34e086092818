"""The defaults and ranges of the problem-file keys (docs/problem-files.md) and the
thresholds docs/answers.md states, read from the schema (casadi_posture/spec/schema.py),
the data files and the constants the code uses (``schema``).

A region's template names a key ``SECTION.KEY`` (``body.stature_m``, ``loads.mass_kg``,
``motion.bvh.max_angle_residual_deg``): ``{d[body.stature_m]}`` is its default (``required``
for a key without one; a key whose schema default is empty takes its data file's value),
``{r[body.stature_m]}`` its range. ``{c[NAME]}`` is a constant as a number (for a format
such as ``{c[achieved_m]:g}``), ``{n[NAME]}`` the same as the pages write numbers.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from typing import Any

from pydantic import BaseModel

from casadi_posture.adjustment.constraint import BLOCKED_FRACTION, HOLD_FRACTION
from casadi_posture.biomech.low_back import limits
from casadi_posture.data import parameters
from casadi_posture.ik.lexicographic import SQP_MAX_ITERATIONS, SQP_RADIUS, LexicographicOptions
from casadi_posture.ik.nullspace import NullspaceOptions
from casadi_posture.ik.result import ACHIEVED_TOLERANCE
from casadi_posture.motion.scaling import MAX_LENGTH_RATIO
from casadi_posture.runs.whatif import MAX_CASES
from casadi_posture.spec import schema
from casadi_posture.spec.overrides import MAX_NESTING

from .regions import Region
from .session import Session

#: The model of each section of a problem file.
SECTIONS: dict[str, type[BaseModel]] = {
    "body": schema.BodySpec,
    "loads": schema.LoadSpec,
    "tasks": schema.PositionTask,  # every task kind shares name, kind and priority
    "fatigue": schema.FatigueSpec,
    "simulation": schema.SimulationSpec,
    "schedule": schema.ScheduleSpec,
    "solver": schema.SolverSpec,
    "motion": schema.MotionSpec,
    "motion.bvh": schema.BvhSpec,
}

#: Keys whose schema default is empty (None): the code takes a data file's parameter.
DATA_DEFAULTS = {
    "fatigue.load_threshold_pct_mvc": ("fatigue", "load_threshold"),
    "fatigue.fatigue_weight": ("comfort", "fatigue_weight"),
}


def number(x: float) -> str:
    """A number as the pages write it: ``1.741``, ``86 400`` (thousands spaced from 10 000
    on), ``1e6``, ``1e-14``, a minus sign ``−``."""
    if float(x).is_integer() and 10_000 <= abs(x) < 1e6:
        text = f"{int(x):,}".replace(",", " ")
    else:
        mantissa, e, exponent = f"{x:g}".partition("e")
        text = f"{mantissa}e{int(exponent)}" if e else mantissa
    return "−" + text[1:] if text.startswith("-") else text


def shown(value: Any) -> str:
    """A default as the tables write it: a number, a string as is, a list in brackets."""
    if isinstance(value, bool) or value is None:
        return str(value).lower()
    if isinstance(value, int | float):
        return number(value)
    if isinstance(value, list):
        return "[" + ", ".join(shown(v) for v in value) + "]"
    return str(value)


@cache
def _property(key: str) -> tuple[dict[str, Any], bool]:
    """The JSON schema of ``SECTION.KEY`` and whether the key is required."""
    section, _, name = key.rpartition(".")
    model = SECTIONS[section].model_json_schema()
    if name not in model["properties"]:
        raise KeyError(f"{key}: no such key in {SECTIONS[section].__name__}")
    return model["properties"][name], name in model.get("required", ())


def _bounds(prop: Mapping[str, Any]) -> Mapping[str, Any]:
    """The part of a property's schema that holds its bounds (a number, one element of an
    optional, or a list's items)."""
    for part in (prop, *prop.get("anyOf", ()), prop.get("items", {})):
        if any(k in part for k in ("minimum", "exclusiveMinimum", "maximum")):
            return part
        if "items" in part and part is not prop:
            return _bounds(part)
    raise KeyError(f"no bounds in {prop}")


def range_text(key: str) -> str:
    """``0.5–2.5`` (both ends included), ``±10 000``, ``0 < x ≤ 1``, ``−0.01 ≤ x < 0``."""
    b = _bounds(_property(key)[0])
    low_open, high_open = "exclusiveMinimum" in b, "exclusiveMaximum" in b
    low = b["exclusiveMinimum"] if low_open else b["minimum"]
    high = b["exclusiveMaximum"] if high_open else b["maximum"]
    if not (low_open or high_open):
        return f"±{number(high)}" if low == -high else f"{number(low)}–{number(high)}"
    return f"{number(low)} {'<' if low_open else '≤'} x {'<' if high_open else '≤'} {number(high)}"


def default_text(key: str) -> str:
    """The key's default (a data file's value where the schema's is empty; ``required``)."""
    prop, required = _property(key)
    if required:
        return "required"
    if prop.get("default") is None:
        if key not in DATA_DEFAULTS:
            raise KeyError(f"{key}: the schema gives no default")
        return shown(parameters.value(*DATA_DEFAULTS[key]))
    return shown(prop["default"])


class _Lookup(dict[str, str]):
    """A mapping computed on first use from a key's name."""

    def __init__(self, make: Any) -> None:
        super().__init__()
        self._make = make

    def __missing__(self, key: str) -> str:
        self[key] = self._make(key)
        return self[key]


def constants() -> dict[str, float]:
    """The numbers the pages state beside the tables, by name."""
    nullspace, lexicographic = NullspaceOptions(), LexicographicOptions()
    low_back = limits()
    return {
        "max_steps": schema.MAX_STEPS,
        "min_time_step_s": schema.MIN_TIME_STEP_S,
        "minutes_at_min_step": schema.MAX_STEPS * schema.MIN_TIME_STEP_S / 60.0,
        "max_nesting": MAX_NESTING,
        "max_position_m": schema.MAX_POSITION_M,
        "max_angle_deg": schema.MAX_ANGLE_DEG,
        "max_direction": schema.MAX_DIRECTION,
        "achieved_m": ACHIEVED_TOLERANCE,
        "nullspace_iterations": nullspace.max_iterations,
        "nullspace_tolerance": nullspace.tolerance,
        "nullspace_damping": nullspace.damping,
        "nullspace_stall_iterations": nullspace.stall_iterations,
        "nullspace_memory": nullspace.acceleration_memory,
        "nullspace_curvature": nullspace.curvature,
        "sqp_radius_rad": SQP_RADIUS,
        "lexicographic_iterations": lexicographic.max_iterations,
        "lexicographic_tolerance": lexicographic.tolerance,
        "sqp_iterations": SQP_MAX_ITERATIONS,
        "load_threshold_pct_mvc": parameters.value("fatigue", "load_threshold"),
        "rest_multiplier": parameters.value("fatigue", "rest_multiplier"),
        "blocked_pct": 100 * BLOCKED_FRACTION,
        "hold_pct": 100 * HOLD_FRACTION,
        "max_length_ratio": MAX_LENGTH_RATIO,
        "design_limit_N": low_back["design"],
        "upper_limit_N": low_back["upper"],
        "max_cases": MAX_CASES,
        "bmi_lowest": parameters.value("slips", "bmi.lowest"),
        "bmi_highest": parameters.value("slips", "bmi.highest"),
        "radians_largest": parameters.value("slips", "radians.largest"),
        "heaviest_load_kg": parameters.value("slips", "load.heaviest"),
        "crossed_hands_m": parameters.value("plausibility", "crossed_hands"),
    }


def values(region: Region, session: Session) -> dict[str, Any]:
    """``d`` and ``r``: every key's default and range, by ``SECTION.KEY``; ``c`` and ``n``:
    the :func:`constants` as numbers and as written."""
    c = constants()
    return {
        "d": _Lookup(default_text),
        "r": _Lookup(range_text),
        "c": c,
        "n": {k: number(v) for k, v in c.items()},
    }
