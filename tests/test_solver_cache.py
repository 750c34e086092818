"""Solvers are built once per problem structure in a worker: cases that differ only in
loads, fatigue settings or targets share the compiled solvers and get the answers of
freshly built ones; a change of body or joint range builds anew."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import PROBLEMS

import casadi_posture as cp
from casadi_posture.ik import solvers
from casadi_posture.ik.solvers import SOLVER_NAMES, cached_solver, make_solver, structure_key
from casadi_posture.problem import load_problem

HOLD = PROBLEMS / "holding_m45.toml"


def test_the_structure_ignores_loads_and_targets_but_not_body_or_ranges() -> None:
    base = load_problem(HOLD).hierarchy()
    heavier = load_problem(HOLD, {"loads[0].mass_kg": 5.0}).hierarchy()
    moved = load_problem(HOLD, {"tasks[0].point_m": [0.3, 0.0, -0.1]}).hierarchy()
    taller = load_problem(HOLD, {"body.stature_m": 1.9}).hierarchy()
    limited = load_problem(HOLD, {"body.dofs.elbow_flexion.range_deg": [0.0, 120.0]})
    key = structure_key(base)
    assert structure_key(heavier) == key == structure_key(moved)
    assert structure_key(taller) != key
    assert structure_key(limited.hierarchy()) != key


@pytest.mark.parametrize("name", SOLVER_NAMES)
def test_a_cached_solver_answers_like_a_fresh_one_on_other_targets(name: str) -> None:
    first = load_problem(HOLD).hierarchy()
    cached_solver(name, first).solve(load_problem(HOLD).posture)  # built and used once
    problem = load_problem(HOLD, {"tasks[0].point_m": [0.3, 0.0, -0.1]})
    second = problem.hierarchy()
    reused = cached_solver(name, second)
    assert reused.hierarchy is second
    compiled = "_buffer" if name == "nullspace" else "_built"
    assert getattr(reused, compiled) is getattr(cached_solver(name, first), compiled)
    fresh = make_solver(name, second).solve(problem.posture)
    again = reused.solve(problem.posture)
    assert np.array_equal(again.q, fresh.q) and again.iterations == fresh.iterations


def test_a_solve_then_a_simulation_in_one_process_answer_as_each_alone() -> None:
    """The frontal elbow's one-DOF line: solve builds its solver for a hierarchy of 1
    parameter, the simulation's has 13 that its residuals partly ignore; both had one
    structure key, and the simulation reused the solve's solver (a ValueError in
    cp.simulate after cp.solve, and in every in-process caller)."""
    problem = load_problem(PROBLEMS / "strategy_frontal_elbow.toml", {"simulation.duration_s": 60})
    solvers._cache.__dict__.pop("solvers", None)
    alone = cp.simulate(problem).summary()
    solvers._cache.__dict__.pop("solvers", None)
    cp.solve(problem)
    assert cp.simulate(problem).summary() == alone
