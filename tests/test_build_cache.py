"""A simulation reuses what it built for an earlier run of the same body, posture, loads and
tasks (simulation._built), and its answer is the one a fresh build gives."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casadi_posture import simulation
from casadi_posture.problem import load_problem
from casadi_posture.simulation import simulate

WALL = Path(__file__).resolve().parents[1] / "problems" / "standing_wall_horizontal.toml"
SHORT = {"simulation.duration_s": 300.0}


def _fresh(problem, solver="nullspace"):
    simulation._builds.__dict__.clear()
    return simulate(problem, solver)


def test_a_second_run_reuses_the_build_and_gives_the_fresh_answer() -> None:
    """The wall hold under the whole-body adjustment, whose runs set effort weights in
    their hierarchy's targets: after a run with another fatigue threshold (the same
    structure, reused), the answer is the fresh build's to the last bit."""
    first = load_problem(WALL, {**SHORT, "fatigue.fatigue_threshold": 0.6})
    second = load_problem(WALL, SHORT)
    expected = _fresh(second)
    _fresh(first)
    kept = simulation._builds.kept[next(iter(simulation._builds.kept))]
    again = simulate(second, "nullspace")
    assert len(simulation._builds.kept) == 1
    assert simulation._builds.kept[next(iter(simulation._builds.kept))] is kept
    np.testing.assert_array_equal(again.timeline.q, expected.timeline.q)
    np.testing.assert_array_equal(again.timeline.fatigue, expected.timeline.fatigue)
    assert [e.kind for e in again.events] == [e.kind for e in expected.events]
    assert any(e.kind == "constraint_on" for e in again.events)  # the weights were set


def test_another_load_or_posture_is_built_anew() -> None:
    base = load_problem(WALL, SHORT)
    _fresh(base)
    heavier = load_problem(WALL, {**SHORT, "loads[0].mass_kg": 3.0})
    simulate(heavier, "nullspace")
    moved = base.with_posture({"elbow_flexion_l": 20.0})
    simulate(moved, "nullspace")
    assert len(simulation._builds.kept) == 3
    expected = _fresh(heavier)
    np.testing.assert_array_equal(simulate(heavier, "nullspace").timeline.q, expected.timeline.q)
