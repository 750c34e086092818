"""The ``casadi-posture`` command line: the group and its commands, one module per kind."""

from casadi_posture.cli import ik, model, runs
from casadi_posture.cli.common import main

__all__ = ["ik", "main", "model", "runs"]
