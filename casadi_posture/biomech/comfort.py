"""How uncomfortable a posture is: the criterion that settles whatever the tasks leave free
(docs/comfort.md).

The measure is a weighted sum of squares, ``C(q) = ‖r(q)‖²``, so both IK solvers take it as
their lowest level: the lexicographic solver minimises it with the levels above kept, the
nullspace solver follows its gradient projected onto what the levels above leave free. Its
rows, each term only when its weight is positive:

    displacement   √(w_d γ_i) (q_i − q_i^N)/R_i                      per DOF i
    limits         √w_l [(1 − d_i⁻/ζ)₊² + (1 − d_i⁺/ζ)₊²]           per DOF i
    effort         √(w_e c_g) τa_i / st_g,  g the half-joint carrying τa_i   per DOF i

with q^N the neutral posture [rad], R_i the DOF's range [rad], γ_i its joint weight,
d_i^∓ = (q_i − q_min)/R_i and (q_max − q_i)/R_i its distance to each limit as a fraction of
the range, ζ the zone near a limit where discomfort rises (``(x)₊ = max(x, 0)``: zero over
the rest of the range, its square (1 − d/ζ)⁴ growing to 1 at the limit), τa the active
torque [N·m], st the strength of its half-joint [N·m] and c_g ≥ 1 the weight of a group's
effort (1, or 1 + k·F_g with F_g its fatigue level under the whole-body adjustment). The
same function builds the rows of numbers and of CasADi symbols.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import casadi as ca
import numpy as np

from casadi_posture.body.tree import BodyModel
from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter, data_name
from casadi_posture.errors import ProblemError

#: The named measures and the terms each one sums.
Measure = Literal["joint_displacement", "discomfort", "discomfort_effort"]
TERMS = ("displacement", "limits", "effort")
MEASURES: dict[str, tuple[str, ...]] = {
    "joint_displacement": ("displacement",),
    "discomfort": ("displacement", "limits"),
    "discomfort_effort": ("displacement", "limits", "effort"),
}
DEFAULT_MEASURE: Measure = "discomfort_effort"


@dataclass(frozen=True)
class ComfortMeasure:
    """A comfort measure on one body: its ``name``, the ``neutral`` posture [rad] and
    ``joint_weights`` γ per DOF, the weight of each term (``term_weights``, 0 for a term the
    measure leaves out), the ``zone`` ζ near a limit [fraction of the range], the fatigue
    weight k of the whole-body adjustment, and the records of where each number comes from."""

    name: str
    neutral: np.ndarray
    joint_weights: np.ndarray
    term_weights: Mapping[str, float]
    zone: float
    fatigue_weight: float
    records: tuple[Parameter, ...] = ()

    @property
    def effort(self) -> bool:
        """Whether the measure counts effort (and so depends on the loads)."""
        return self.term_weights["effort"] > 0.0

    def rows(
        self,
        body: BodyModel,
        q: ca.SX | np.ndarray,
        neutral: ca.SX | np.ndarray,
        active: ca.SX | np.ndarray | None = None,
        strength: ca.SX | np.ndarray | None = None,
        effort_weights: ca.SX | np.ndarray | None = None,
    ) -> ca.SX | ca.DM:
        """The residual r whose squared norm is the measure, at posture ``q`` [rad] with the
        ``neutral`` posture [rad]; effort needs the ``active`` torque per DOF [N·m], the
        ``strength`` per half-joint [N·m] (positive group of each DOF first) and the
        ``effort_weights`` c_g per half-joint (default 1)."""
        lower, upper = body.lower, body.upper
        span = upper - lower
        w = self.term_weights
        parts = []
        if w["displacement"] > 0.0:
            scale = np.sqrt(w["displacement"] * self.joint_weights) / span
            parts.append(ca.DM(scale) * (q - neutral))
        if w["limits"] > 0.0:
            near_lower = ca.fmax(0.0, 1.0 - (q - lower) / (span * self.zone))
            near_upper = ca.fmax(0.0, 1.0 - (upper - q) / (span * self.zone))
            parts.append(math.sqrt(w["limits"]) * (near_lower**2 + near_upper**2))
        if w["effort"] > 0.0:
            if active is None or strength is None:
                raise ValueError("the effort term needs the active torque and the strength")
            c = np.ones(2 * body.n) if effort_weights is None else effort_weights
            positive = ca.sqrt(c[0::2]) * active / strength[0::2]
            negative = ca.sqrt(c[1::2]) * active / strength[1::2]
            parts.append(math.sqrt(w["effort"]) * ca.if_else(active >= 0, positive, negative))
        return ca.vertcat(*parts)

    def value(self, body: BodyModel, q: np.ndarray, **torques: np.ndarray) -> float:
        """C(q) at a posture ``q`` [rad] (with the torques ``rows`` needs for effort)."""
        r = np.asarray(self.rows(body, q, self.neutral, **torques), dtype=float)
        return float(r.ravel() @ r.ravel())


def neutral_posture(body: BodyModel, given: Mapping[str, float] | None = None) -> np.ndarray:
    """The neutral posture of ``body`` [rad]: ``given`` [deg] per DOF name, else the shipped
    neutral angle of the DOF's name without its side suffix; a DOF with neither raises
    ``ProblemError`` (key ``neutral_deg``)."""
    return _per_dof(body, "neutral", given or {}, "neutral_deg", math.radians)[0]


def comfort_measure(
    body: BodyModel,
    name: str = DEFAULT_MEASURE,
    *,
    weights: Mapping[str, float] | None = None,
    joint_weights: Mapping[str, float] | None = None,
    neutral_deg: Mapping[str, float] | None = None,
    key: str = "comfort",
) -> ComfortMeasure:
    """The measure ``name`` on ``body`` with the shipped data (``data/comfort.toml``) and what a
    problem file sets: term ``weights``, ``joint_weights`` γ and ``neutral_deg`` per DOF
    (unknown names and DOFs without data raise ``ProblemError`` under ``key``)."""
    if name not in MEASURES:
        raise ProblemError(None, f"{key}.measure", name, f"one of {list(MEASURES)}")
    given = dict(weights or {})
    for term in given:
        if term not in MEASURES[name]:
            raise ProblemError(
                None,
                f"{key}.weights.{term}",
                given[term],
                f"no weight: {name} has only the terms {list(MEASURES[name])}",
            )
    table = parameters.load("comfort")
    terms = {t: 0.0 for t in TERMS}
    records = []
    for term in MEASURES[name]:
        record = table[f"comfort.term.{term}"]
        if term in given:
            record = record.overridden(given[term], f"{key}.weights.{term}")
        terms[term] = float(record.value)
        records.append(record)
    neutral, neutral_records = _per_dof(
        body, "neutral", neutral_deg or {}, f"{key}.neutral_deg", math.radians
    )
    gamma, gamma_records = _per_dof(
        body, "joint_weight", joint_weights or {}, f"{key}.joint_weights", float
    )
    _inside(body, neutral, f"{key}.neutral_deg")
    zone, fatigue = table["comfort.limit_zone"], table["comfort.fatigue_weight"]
    return ComfortMeasure(
        name,
        neutral,
        gamma,
        terms,
        float(zone.value),
        float(fatigue.value),
        (*records, *neutral_records, *gamma_records, zone, fatigue),
    )


def _per_dof(
    body: BodyModel, table_name: str, given: Mapping[str, float], key: str, convert: object
) -> tuple[np.ndarray, list[Parameter]]:
    """Per DOF the ``given`` value, else the shipped ``comfort.<table_name>.<dof>``, through
    ``convert``; with the records."""
    for name in given:
        if name not in body.index:
            raise ProblemError(None, f"{key}.{name}", name, f"a DOF of {body.name}")
    table = parameters.load("comfort")
    unit = "deg" if table_name == "neutral" else "1"
    values, records = [], []
    for dof in body.dofs:
        if dof.name in given:
            where = f"{key}.{dof.name}"
            record = Parameter(
                f"comfort.{table_name}.{dof.name}", given[dof.name], unit, where, "user"
            )
        else:
            record = table.get(f"comfort.{table_name}.{data_name(dof.name)}")
        if record is None:
            expected = f"a value for DOF {dof.name} (no shipped {table_name} for it)"
            raise ProblemError(None, f"{key}.{dof.name}", None, expected)
        values.append(convert(record.value))  # type: ignore[operator]
        records.append(record)
    return np.array(values, dtype=float), records


def _inside(body: BodyModel, neutral: np.ndarray, key: str) -> None:
    """Refuse a neutral angle outside its DOF's range."""
    for dof, angle in zip(body.dofs, neutral, strict=True):
        if not dof.lower - 1e-12 <= angle <= dof.upper + 1e-12:
            raise ProblemError(
                None,
                f"{key}.{dof.name}",
                round(math.degrees(angle), 6),
                f"an angle within the range [{math.degrees(dof.lower):g}, "
                f"{math.degrees(dof.upper):g}] deg",
            )
