"""The ``casadi-posture`` command line: the group and its commands, one module per kind."""

from casadi_posture.cli import (
    design,
    ik,
    model,
    motion,
    population,
    runs,
    schedule,
    sensitivity,
)
from casadi_posture.cli.common import main

__all__ = [
    "design",
    "ik",
    "main",
    "model",
    "motion",
    "population",
    "runs",
    "schedule",
    "sensitivity",
]
