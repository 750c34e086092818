"""The ``casadi-posture`` command line: the group and its commands, one module per kind."""

from . import ik, model, runs
from .common import main

__all__ = ["ik", "main", "model", "runs"]
