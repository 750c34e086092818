"""External loads held or applied at body landmarks: point masses, forces and moments."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

Vector3 = tuple[float, float, float]

#: Numbers per load in the parameter vector of the torque functions:
#: mass [kg], force [N] (3, world), moment [N·m] (3, world).
LOAD_PARAMETERS = 7


@dataclass(frozen=True)
class Load:
    """A load at landmark ``at``: a point ``mass`` [kg] under gravity, a ``force`` [N]
    and a pure ``moment`` [N·m], both in the world frame."""

    name: str
    at: str
    mass: float = 0.0
    force: Vector3 = (0.0, 0.0, 0.0)
    moment: Vector3 = (0.0, 0.0, 0.0)


def pack(loads: Sequence[Load]) -> np.ndarray:
    """The loads as the parameter vector of the torque functions (7 numbers per load)."""
    rows = [[load.mass, *load.force, *load.moment] for load in loads]
    return np.asarray(rows, dtype=float).reshape(-1)
