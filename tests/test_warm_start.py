"""While the whole-body adjustment's load bound moves the posture step after step, each
step's IK starts from the posture extrapolated along the last step's change
(simulation._predicted): the same answers as starting from the last posture, in fewer
iterations, with either solver."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casadi_posture import simulation
from casadi_posture.problem import load_problem
from casadi_posture.simulation import simulate

WALL = Path(__file__).resolve().parents[1] / "problems" / "standing_wall_horizontal.toml"


def _both(monkeypatch, problem, solver):
    """The run with the predictor, and the run with every step started at the last posture."""
    predicted = simulate(problem, solver)
    with monkeypatch.context() as patch:
        patch.setattr(simulation, "_predicted", lambda *args: None)
        plain = simulate(problem, solver)
    return predicted, plain


@pytest.mark.parametrize(
    ("solver", "fewer", "atol"),
    [
        # 1387 iterations from the last posture, 357 from the predicted one
        ("nullspace", 0.5, 1e-6),
        # 2187 and 732; IPOPT stops at its own tolerance, postures agree to 1e-5 rad
        ("lexicographic", 0.5, 1e-5),
    ],
)
def test_the_predicted_start_gives_the_same_run_in_fewer_iterations(
    monkeypatch, solver, fewer, atol
) -> None:
    """The 29-DOF standing wall hold until the elbow flexors give out (515 s)."""
    problem = load_problem(WALL, {"simulation.duration_s": 520.0})
    predicted, plain = _both(monkeypatch, problem, solver)
    assert any(e.kind == "constraint_on" for e in plain.events)  # the predictor had work
    assert [(e.time_s, e.kind, e.half_joint) for e in predicted.events] == [
        (e.time_s, e.kind, e.half_joint) for e in plain.events
    ]
    np.testing.assert_allclose(predicted.timeline.q, plain.timeline.q, atol=atol)
    np.testing.assert_allclose(predicted.timeline.fatigue, plain.timeline.fatigue, atol=atol)
    assert predicted.ik_failures == plain.ik_failures == 0
    assert predicted.ik_iterations < fewer * plain.ik_iterations, (
        predicted.ik_iterations,
        plain.ik_iterations,
    )


def test_the_paper_strategy_starts_from_the_last_posture(monkeypatch) -> None:
    """Under the paper's plane the predictor cost iterations: it is not used there."""
    problem = load_problem(
        WALL.with_name("holding_horizontal.toml"), {"simulation.duration_s": 300.0}
    )
    predicted, plain = _both(monkeypatch, problem, "nullspace")
    assert any(e.kind == "constraint_on" for e in plain.events)
    assert predicted.ik_iterations == plain.ik_iterations
    np.testing.assert_array_equal(predicted.timeline.q, plain.timeline.q)
