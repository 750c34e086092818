"""The two IK solvers by name, configured from a problem file's ``[solver]`` table, and
built once per problem structure in each worker."""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
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

    def rebind(self, hierarchy: TaskHierarchy) -> Solver:
        """The same compiled solver on ``hierarchy``, a hierarchy of the same structure (other
        target values), with no memory of earlier solves."""
        ...


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


#: Problem structures whose solvers a worker keeps (a what-if grid varies loads, strategies
#: or fatigue settings far more often than the body or the tasks).
CACHED_STRUCTURES = 4
_cache = threading.local()


def structure_key(hierarchy: TaskHierarchy) -> str:
    """A hierarchy's structure: the SHA-256 of its compiled residual and Jacobian function's
    fingerprint (its sizes, its number of parameters, sparsity and instruction count, and
    its values at one fixed pseudo-random point, which differ for another geometry, other
    masses or other kinds of task, never for other targets, the function's parameters) and
    of the joint ranges (which the solvers build in). Two different functions agree at a
    random point with probability zero; serialising the function instead costs 0.07 s at
    29 DOF."""
    body, f = hierarchy.body, hierarchy.function
    rng = np.random.default_rng(_FINGERPRINT_SEED)
    values = f(rng.uniform(-1.0, 1.0, body.n), rng.uniform(-1.0, 1.0, hierarchy.p.numel()))
    # the parameters' number too: a function may ignore some (a solver built for one target
    # then read 13 of a hierarchy's)
    digest = hashlib.sha256(
        f"{f.n_instructions()} {hierarchy.sizes} {hierarchy.p.numel()}".encode()
    )
    for value in values:
        digest.update(np.asarray(value.sparsity().get_triplet()).tobytes())
        digest.update(np.asarray(value.nonzeros()).tobytes())
    digest.update(np.concatenate([body.lower, body.upper]).tobytes())
    return digest.hexdigest()


#: The seed of the point ``structure_key`` evaluates a hierarchy at.
_FINGERPRINT_SEED = 20080601


def cached_solver(name: str, hierarchy: TaskHierarchy, spec: SolverSpec | None = None) -> Solver:
    """Solver ``name`` on ``hierarchy``, built once per problem structure, solver and options
    in this thread (a batch worker runs many cases of one structure) and rebound to this
    hierarchy's targets, with no memory of the cases before."""
    check_solver(name)
    key = (name, None if spec is None else spec.model_dump_json(), structure_key(hierarchy))
    if not hasattr(_cache, "solvers"):
        _cache.solvers = OrderedDict()
    solvers: OrderedDict = _cache.solvers
    if key in solvers:
        solvers.move_to_end(key)
        return solvers[key].rebind(hierarchy)
    solver = make_solver(name, hierarchy, spec)
    solvers[key] = solver
    while len(solvers) > CACHED_STRUCTURES:
        solvers.popitem(last=False)
    return solver.rebind(hierarchy)
