"""Segment inertia of de Leva (1996), Table 4, scaled to a body of given stature and mass.

Mass scales with body mass; length with stature (geometric similarity), and the centre of mass
and radii of gyration with length. The numbers live in ``data/anthropometry_de_leva_1996.toml``.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace
from functools import cache
from importlib import resources
from typing import Any, Literal, Protocol, get_args

from casadi_posture.data import parameters
from casadi_posture.data.parameters import Parameter
from casadi_posture.errors import ProblemError

Sex = Literal["male", "female"]

_STEM = "anthropometry_de_leva_1996"
_AXES = ("sagittal", "transverse", "longitudinal")


class SegmentGeometry(Protocol):
    """What a builder needs of a segment: ``length`` [m], ``mass`` [kg], ``com_distance`` [m]."""

    length: float
    mass: float

    @property
    def com_distance(self) -> float: ...


@dataclass(frozen=True)
class SegmentInertia:
    """One body segment scaled to a body (de Leva 1996, Table 4).

    ``radii_of_gyration`` [m] are about the sagittal (antero-posterior), transverse
    (medio-lateral) and longitudinal axes through the centre of mass; flexion in the sagittal
    plane turns about the transverse axis. ``parameters`` records each scaled value with its
    derivation.
    """

    name: str
    length: float
    mass: float
    com_fraction: float
    radii_of_gyration: tuple[float, float, float]
    proximal: str
    distal: str
    parameters: tuple[Parameter, ...]

    @property
    def com_distance(self) -> float:
        """Distance [m] of the centre of mass from the proximal end point."""
        return self.com_fraction * self.length


@cache
def _table() -> dict[str, Any]:
    text = resources.files("casadi_posture.data").joinpath(f"{_STEM}.toml").read_text("utf-8")
    return tomllib.loads(text)


SEGMENTS: tuple[str, ...] = tuple(key for key in _table()["male"] if key != "reference")


def _data(sex: Sex, name: str) -> Parameter:
    return parameters.load(_STEM)[f"{_STEM}.{sex}.{name}"]


def _check_choice(key: str, value: Any, allowed: tuple[str, ...]) -> None:
    if value not in allowed:
        raise ProblemError(None, key, value, "one of " + ", ".join(map(repr, allowed)))


def _check_positive(key: str, value: Any, unit: str) -> None:
    is_real = isinstance(value, int | float) and not isinstance(value, bool)
    if not (is_real and math.isfinite(value) and value > 0):
        raise ProblemError(None, key, value, f"a positive finite number [{unit}]")


def reference_body(sex: Sex) -> tuple[float, float]:
    """Mean stature [m] and body mass [kg] of de Leva's (1996) reference sample of ``sex``."""
    _check_choice("sex", sex, get_args(Sex))
    return _data(sex, "reference.stature").value, _data(sex, "reference.body_mass").value


def segment_inertia(name: str, *, sex: Sex, stature: float, body_mass: float) -> SegmentInertia:
    """Segment ``name`` (one of ``SEGMENTS``) of a body of ``stature`` [m] and ``body_mass`` [kg].

    Raises ``ProblemError`` for an unknown segment or sex and a non-positive stature or mass.
    """
    reference_stature, _ = reference_body(sex)
    _check_choice("segment", name, SEGMENTS)
    _check_positive("stature", stature, "m")
    _check_positive("body_mass", body_mass, "kg")

    def data(quantity: str) -> Parameter:
        return _data(sex, f"{name}.{quantity}")

    reference_length = data("length")
    mass_fraction = data("mass_fraction").value
    com_fraction = data("com_fraction").value
    radius_fractions = [data(f"r_{axis}").value for axis in _AXES]
    length = reference_length.value * stature / reference_stature
    mass = mass_fraction * body_mass
    sagittal, transverse, longitudinal = (r * length for r in radius_fractions)
    radii = (sagittal, transverse, longitudinal)

    def scaled(quantity: str, value: float, unit: str, derivation: str) -> Parameter:
        return Parameter(
            name=f"segment.{name}.{quantity}",
            value=value,
            unit=unit,
            source=f"{reference_length.source} ({sex}): {derivation}",
            status=reference_length.status,
            evidence=reference_length.evidence,
        )

    of_length = f"× length {length:.4g} m"
    records = (
        scaled(
            "length",
            length,
            "m",
            f"length {reference_length.value:g} m × stature {stature:g} m"
            f" / reference stature {reference_stature:g} m",
        ),
        scaled("mass", mass, "kg", f"mass fraction {mass_fraction:g} × body mass {body_mass:g} kg"),
        scaled(
            "com_distance", com_fraction * length, "m", f"COM fraction {com_fraction:g} {of_length}"
        ),
        *(
            scaled(
                f"radius_of_gyration.{axis}", r, "m", f"{axis} radius fraction {f:g} {of_length}"
            )
            for axis, f, r in zip(_AXES, radius_fractions, radii, strict=True)
        ),
    )
    end_points = _table()[sex][name]
    return SegmentInertia(
        name=name,
        length=length,
        mass=mass,
        com_fraction=com_fraction,
        radii_of_gyration=radii,
        proximal=end_points["proximal"],
        distal=end_points["distal"],
        parameters=records,
    )


def resized(segment: SegmentInertia, length: Parameter) -> SegmentInertia:
    """``segment`` at the ``length`` [m] of another source: its centre of mass and radii of
    gyration keep their fractions of the length, its mass stays."""
    scale = length.value / segment.length
    ratio = f", × length {length.value:.4g} m / {segment.length:.4g} m"

    def scaled(record: Parameter) -> Parameter:
        return replace(
            record,
            value=record.value * scale,
            source=record.source + ratio,
            status=length.status,
            evidence="+".join(dict.fromkeys((record.evidence, length.evidence))),
        )

    kept = (f"segment.{segment.name}.length", f"segment.{segment.name}.mass")
    records = tuple(
        length if r.name == kept[0] else r if r.name == kept[1] else scaled(r)
        for r in segment.parameters
    )
    sagittal, transverse, longitudinal = (r * scale for r in segment.radii_of_gyration)
    return replace(
        segment,
        length=length.value,
        radii_of_gyration=(sagittal, transverse, longitudinal),
        parameters=records,
    )
