"""Endurance models: the maximum time a constant static load can be held, selectable by name.

A load is the normalized torque ``T_N`` of a half-joint in %MVC (docs/model.md); ``f = T_N/100`` is
the same load as a fraction of MVC. Loads above 100 %MVC are not clipped: every model
extrapolates its own curve there (see each class). Coefficients live in
``data/endurance.toml`` (sources in docs/sources.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import casadi as ca
import numpy as np
from numpy.polynomial import polynomial
from numpy.typing import ArrayLike

from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter
from casadi_posture.errors import ProblemError

SECONDS_PER_MINUTE = 60.0
PERCENT = 100.0
DEFAULT_ENDURANCE_MODEL = "manenica"


class EnduranceModel(Protocol):
    """Maximum holding time of a constant static load by a muscle group of a joint region."""

    name: str

    def endurance_time_s(self, load_pct_mvc: ArrayLike, region: Regions) -> np.ndarray:
        """Endurance time [s] of each load [%MVC] held by a muscle group of ``region`` (one
        name, or one per load: every group of a body in one call)."""
        ...

    def parameters(self, regions: Iterable[str]) -> list[Parameter]:
        """The parameter records the model uses for these joint regions."""
        ...

    def expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> ca.SX:
        """The endurance [s] as a CasADi expression of a load [%MVC] that the model limits
        (above 0 %MVC, and above the sustainable level where there is one), each coefficient
        given by ``value(record)``: its number, or a symbol to differentiate with respect to."""
        ...


#: A joint region's name, or one per load.
Regions = str | Sequence[str]

#: A parameter record's value in an expression: a number, or a CasADi symbol.
Value = Callable[[Parameter], ca.SX | float]


def numeric(record: Parameter) -> float:
    """A record's own value (the ``Value`` of a plain evaluation)."""
    return record.value


def _data(name: str) -> Parameter:
    return parameters.load("endurance")[f"endurance.{name}"]


@dataclass(frozen=True)
class Manenica:
    """Manenica 1986 (paper eq. 6): ``mht = exp(a − b·T_N)`` [min], ``T_N`` in %MVC.

    Region-independent and a pure exponential: finite at 0 %MVC (``exp(a)`` = 14.88 min),
    10 s at 100 %MVC, and shorter still above it.
    """

    a: Parameter
    b: Parameter
    name: str = field(default="manenica", init=False)

    @classmethod
    def from_data(cls) -> Manenica:
        """The model with the shipped coefficients (``endurance.manenica``)."""
        return cls(a=_data("manenica.a"), b=_data("manenica.b"))

    def endurance_time_s(self, load_pct_mvc: ArrayLike, region: Regions) -> np.ndarray:
        """Maximum holding time [s] of each load [%MVC]; ``region`` is ignored."""
        load = np.asarray(load_pct_mvc, dtype=float)
        return SECONDS_PER_MINUTE * np.exp(self.a.value - self.b.value * load)

    def expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> ca.SX:
        """``60·exp(a − b·T_N)`` [s]."""
        return SECONDS_PER_MINUTE * ca.exp(value(self.a) - value(self.b) * load_pct_mvc)

    def parameters(self, regions: Iterable[str]) -> list[Parameter]:
        """``a`` and ``b``, whatever the regions."""
        return [self.a, self.b]


@dataclass(frozen=True)
class FreyLawAvin:
    """Frey-Law & Avin 2010 power model per joint region: ``ET = b0·f^b1`` [s], ``f = T_N/100``.

    Table 2 of the paper (fitted on 10-100 %MVC). ``f ≤ 0`` gives ``inf``; above 100 %MVC the
    power law goes on (``ET < b0``).
    """

    table: Mapping[str, Parameter]
    name: str = field(default="frey_law_avin", init=False)
    _arrays: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @classmethod
    def from_data(cls) -> FreyLawAvin:
        """The model with the shipped table (``endurance.frey_law_avin.<region>.b0/b1``)."""
        return cls(parameters.load("endurance"))

    def _coefficients(self, region: str) -> tuple[Parameter, Parameter]:
        """``b0`` and ``b1`` of ``region`` (a region without data: the general fit)."""
        prefix = "endurance.frey_law_avin."
        return (
            parameters.regional(self.table, prefix, region, "b0"),
            parameters.regional(self.table, prefix, region, "b1"),
        )

    def endurance_time_s(self, load_pct_mvc: ArrayLike, region: Regions) -> np.ndarray:
        """Endurance time [s] of each load [%MVC] for the muscle groups of ``region`` (one
        region, or one per load)."""
        b0, b1 = self._values(region)
        fraction = np.asarray(load_pct_mvc, dtype=float) / PERCENT
        positive = fraction > 0
        return np.where(positive, b0 * np.where(positive, fraction, 1.0) ** b1, np.inf)

    def _values(self, region: Regions) -> tuple[np.ndarray, np.ndarray]:
        """The numbers ``b0`` and ``b1`` of ``region``, or of each region (looked up once)."""
        key = region if isinstance(region, str) else tuple(region)
        if key not in self._arrays:
            names = [key] if isinstance(key, str) else key
            pairs = [self._coefficients(name) for name in names]
            b0, b1 = (np.array([pair[i].value for pair in pairs]) for i in (0, 1))
            self._arrays[key] = (b0[0], b1[0]) if isinstance(key, str) else (b0, b1)
        return self._arrays[key]

    def expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> ca.SX:
        """``b0·f^b1`` [s] of ``region``, ``f = T_N/100 > 0``."""
        b0, b1 = self._coefficients(region)
        return value(b0) * (load_pct_mvc / PERCENT) ** value(b1)

    def parameters(self, regions: Iterable[str]) -> list[Parameter]:
        """``b0`` and ``b1`` of each distinct region, in order of first appearance."""
        return [p for region in dict.fromkeys(regions) for p in self._coefficients(region)]


@dataclass(frozen=True)
class Rohmert:
    """Rohmert 1960 endurance curve: ``ET = c0 + c1/f + c2/f² + c3/f³`` [min], ``f = T_N/100``.

    Valid above the sustainable level (15 %MVC); at or below it the load can be held
    indefinitely (``inf``). The polynomial turns negative just above 109 %MVC, so loads above
    100 %MVC keep the 100 %MVC value (0.1 min).
    """

    coefficients: Parameter
    sustainable_level: Parameter
    name: str = field(default="rohmert", init=False)

    @classmethod
    def from_data(cls) -> Rohmert:
        """The model with the shipped coefficients (``endurance.rohmert``)."""
        return cls(
            coefficients=_data("rohmert.coefficients"),
            sustainable_level=_data("rohmert.sustainable_level"),
        )

    def endurance_time_s(self, load_pct_mvc: ArrayLike, region: Regions) -> np.ndarray:
        """Endurance time [s] of each load [%MVC]; ``region`` is ignored."""
        load = np.asarray(load_pct_mvc, dtype=float)
        held = load > self.sustainable_level.value
        inverse = PERCENT / np.clip(load, self.sustainable_level.value, PERCENT)
        minutes = polynomial.polyval(inverse, self.coefficients.value)
        return np.where(held, SECONDS_PER_MINUTE * minutes, np.inf)

    def expression(self, load_pct_mvc: ca.SX, region: str, value: Value) -> ca.SX:
        """``60·Σ c_k·(100/T_N)^k`` [s] for a load between the sustainable level and 100 %MVC
        (the 100 %MVC value above it)."""
        inverse = PERCENT / ca.fmin(load_pct_mvc, PERCENT)
        c = value(self.coefficients)
        return SECONDS_PER_MINUTE * sum(
            c[k] * inverse**k for k in range(len(self.coefficients.value))
        )

    def parameters(self, regions: Iterable[str]) -> list[Parameter]:
        """The coefficients and the sustainable level, whatever the regions."""
        return [self.coefficients, self.sustainable_level]


ENDURANCE_MODELS: dict[str, Callable[[], EnduranceModel]] = {
    "manenica": Manenica.from_data,
    "frey_law_avin": FreyLawAvin.from_data,
    "rohmert": Rohmert.from_data,
}


def endurance_model(name: str) -> EnduranceModel:
    """The endurance model called ``name`` (a key of ``ENDURANCE_MODELS``)."""
    if name not in ENDURANCE_MODELS:
        raise ProblemError(None, "fatigue.endurance", name, f"one of {', '.join(ENDURANCE_MODELS)}")
    return ENDURANCE_MODELS[name]()


def half_joint_endurance_s(model: EnduranceModel, load_pct_mvc: float, region: str) -> float:
    """Endurance [s] of a half-joint at ``load_pct_mvc``: infinite when it carries nothing
    (the antagonist of the group that holds the load), else the model's time."""
    if load_pct_mvc == 0.0:
        return math.inf
    return float(model.endurance_time_s(load_pct_mvc, region))
