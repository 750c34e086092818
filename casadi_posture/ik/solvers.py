"""The two IK solvers by name, configured from a problem file's ``[solver]`` table."""

from __future__ import annotations

from dataclasses import replace
from typing import Protocol

import numpy as np

from casadi_posture.errors import ProblemError
from casadi_posture.ik.hierarchy import Inequality, TaskHierarchy
from casadi_posture.ik.lexicographic import LexicographicOptions, LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceOptions, NullspaceSolver
from casadi_posture.ik.result import IKResult
from casadi_posture.spec.schema import SolverSpec

SOLVER_NAMES = ("nullspace", "lexicographic")


class Solver(Protocol):
    name: str
    hierarchy: TaskHierarchy

    def solve(self, q0: np.ndarray, inequality: Inequality | None = None) -> IKResult: ...


def make_solver(name: str, hierarchy: TaskHierarchy, spec: SolverSpec | None = None) -> Solver:
    """Build solver ``name`` on ``hierarchy``; options from ``spec`` apply when its name matches."""
    given = {}
    if spec is not None and spec.name == name:
        given = {
            k: v
            for k, v in (
                ("max_iterations", spec.max_iterations),
                ("tolerance", spec.tolerance),
                ("damping", spec.damping),
            )
            if v is not None
        }
    check_solver(name)
    if name == "nullspace":
        return NullspaceSolver(hierarchy, replace(NullspaceOptions(), **given))
    return LexicographicSolver(hierarchy, replace(LexicographicOptions(), **given))


def check_solver(name: str | None, file: object = None, key: str = "solver") -> None:
    """Refuse a solver name other than ``SOLVER_NAMES`` (None: the problem file's)."""
    if name is not None and name not in SOLVER_NAMES:
        raise ProblemError(file, key, name, f"one of {list(SOLVER_NAMES)}")
