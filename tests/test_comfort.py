"""The comfort measure (biomech/comfort.py) and the whole-body fatigue adjustment
(adjustment/whole_body.py): the gradient against finite differences, the postures it gives
on the 3-D bodies (symmetric tasks symmetric, an unloaded body neutral, an idle arm
hanging), both solvers on every shipped 3-D problem, and the adjustment's run."""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import casadi_posture as cp
from casadi_posture.biomech.comfort import comfort_measure, neutral_posture
from casadi_posture.errors import ProblemError
from casadi_posture.ik.lexicographic import LexicographicSolver
from casadi_posture.ik.nullspace import NullspaceSolver
from casadi_posture.problem import problem_from_data

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
THREE_D = sorted(
    p.stem for p in PROBLEMS.glob("*.toml") if p.stem.startswith(("standing_", "seated_"))
)


def _solve(problem: cp.Problem, solver: str) -> np.ndarray:
    hierarchy = problem.hierarchy()
    kind = NullspaceSolver if solver == "nullspace" else LexicographicSolver
    result = kind(hierarchy).solve(problem.posture)
    assert result.success, result.status
    return result.q


def test_the_gradient_equals_finite_differences() -> None:
    """∇C by AD against central differences at a posture away from the neutral one, every
    term on (the limit zone entered by two joints)."""
    problem = cp.load(PROBLEMS / "standing_shelf_box.toml")
    body = problem.body
    task = next(t for level in problem.hierarchy().levels for t in level if t.name == "comfort")
    p = ca.SX.sym("p", task.targets().size)
    value = ca.sumsqr(task.residual(body, p))
    f = ca.Function("c", [body.q, p], [value, ca.gradient(value, body.q)])
    rng = np.random.default_rng(7)
    q = np.clip(rng.normal(0.0, 0.3, body.n), body.lower + 0.02, body.upper - 0.02)
    q[body.index["knee_flexion_r"]] = np.radians(-8.0)  # within the zone of its limit
    q[body.index["elbow_flexion_l"]] = np.radians(3.0)
    c, grad = (np.asarray(v, dtype=float).ravel() for v in f(q, task.targets()))
    h = 1e-6
    for j in range(body.n):
        step = np.zeros(body.n)
        step[j] = h
        fd = (float(f(q + step, task.targets())[0]) - float(f(q - step, task.targets())[0])) / (
            2 * h
        )
        assert grad[j] == pytest.approx(fd, rel=1e-5, abs=1e-7), body.dofs[j].name
    assert c[0] > 0


def test_the_value_is_the_sum_of_its_terms_by_hand() -> None:
    """On the 2-DOF arm with 'discomfort': (q − q_N)/R squared per DOF, plus the limit term
    (1 − d/ζ)⁴ of a joint within ζ of its limit, by hand."""
    problem = cp.load(PROBLEMS / "holding_m45.toml")
    body = problem.body
    measure = comfort_measure(body, "discomfort")
    q = np.array([np.radians(30.0), np.radians(5.0)])  # elbow 5° from its 0° limit
    span = body.upper - body.lower
    by_hand = float(np.sum(((q - measure.neutral) / span) ** 2))
    d = (q[1] - body.lower[1]) / span[1]
    by_hand += (1 - d / measure.zone) ** 4
    assert measure.value(body, q) == pytest.approx(by_hand, rel=1e-12)


@pytest.mark.parametrize("solver", ["nullspace", "lexicographic"])
def test_a_symmetric_task_gives_a_symmetric_posture(solver: str) -> None:
    """The box at the shelf with both hands: every left DOF equals its right one to 1e-6°
    (the issue's bound is 1°; the upright posture task gave 14° and 21°)."""
    problem = cp.load(PROBLEMS / "standing_shelf_box.toml")
    q = np.degrees(_solve(problem, solver))
    index = problem.body.index
    for name, i in index.items():
        if name.endswith("_r"):
            assert q[i] == pytest.approx(q[index[name[:-2] + "_l"]], abs=1e-6), name


def test_an_unloaded_standing_body_stands_in_its_neutral_posture() -> None:
    """Feet and balance (the centre of mass where the neutral posture has it) only: with the
    displacement term alone the body stands exactly in its neutral posture; with the default
    measure within 5° of it (the knees leave the zone of their −10° limit)."""
    base = cp.load(PROBLEMS / "standing_shelf_box.toml").data
    base = {**base, "posture_deg": {"elbow_flexion_r": 10.0, "elbow_flexion_l": 10.0}}
    tasks = [t for t in base["tasks"] if t["kind"] in ("feet", "com")]
    for measure, tolerance in (("joint_displacement", 1e-6), ("discomfort_effort", 5.0)):
        comfort = {"name": "comfort", "kind": "comfort", "priority": 2, "measure": measure}
        data = {**base, "loads": [], "tasks": [*tasks, comfort]}
        problem = problem_from_data(data, "neutral.toml")
        neutral = np.degrees(neutral_posture(problem.body))
        for solver in ("nullspace", "lexicographic"):
            q = np.degrees(_solve(problem, solver))
            assert np.abs(q - neutral).max() < tolerance, (measure, solver)


def test_the_idle_arm_hangs() -> None:
    """At the wall the left arm carries nothing: it hangs (shoulder within 5° of 0°, the
    elbow relaxed within 5° of its 10°)."""
    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml")
    q = np.degrees(_solve(problem, "nullspace"))
    index = problem.body.index
    for name in ("shoulder_flexion_l", "shoulder_abduction_l", "shoulder_rotation_l"):
        assert abs(q[index[name]]) < 5.0, name
    assert abs(q[index["elbow_flexion_l"]] - 10.0) < 5.0


@pytest.mark.parametrize("name", THREE_D)
def test_both_solvers_reach_the_same_posture(name: str) -> None:
    """Every shipped 3-D problem: the same posture from the file's start (0.01°)."""
    problem = cp.load(PROBLEMS / f"{name}.toml")
    a, b = (np.degrees(_solve(problem, s)) for s in ("nullspace", "lexicographic"))
    assert np.abs(a - b).max() < 0.01


def test_a_comfort_task_shares_no_level_and_comes_last() -> None:
    data = cp.load(PROBLEMS / "standing_shelf_box.toml").data
    tasks = [dict(t) for t in data["tasks"]]
    tasks[-1]["priority"] = 2
    with pytest.raises(ProblemError, match=r"tasks\[4\]\.priority"):
        problem_from_data({**data, "tasks": tasks}, "x.toml")
    tasks[-1]["priority"] = 3
    tasks[-1]["neutral_deg"] = {"elbow_flexion_q": 10.0}
    with pytest.raises(ProblemError, match=r"neutral_deg\.elbow_flexion_q"):
        problem_from_data({**data, "tasks": tasks}, "x.toml")


def test_the_whole_body_adjustment_needs_an_effort_comfort_level() -> None:
    problem = cp.load(PROBLEMS / "holding_m45.toml", {"fatigue.adjustment": "whole_body"})
    with pytest.raises(ProblemError, match=r"fatigue\.adjustment"):
        cp.simulate(problem)


@pytest.mark.slow
def test_the_whole_body_adjustment_at_the_wall() -> None:
    """The 0° wall hold: at the threshold the shoulder flexors' load is lowered with the wrist
    kept on the line (levels 1-2) and the dot given up; both solvers give the same events at
    the same seconds and no step falls back."""
    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml", {"simulation.duration_s": 300.0})
    runs = {s: cp.simulate(problem, s).result for s in ("nullspace", "lexicographic")}
    events = {s: [(e.time_s, e.kind, e.half_joint) for e in r.events] for s, r in runs.items()}
    assert events["nullspace"] == events["lexicographic"]
    run = runs["nullspace"]
    assert run.ik_fallbacks == 0
    on = next(e for e in run.events if e.kind == "constraint_on")
    assert on.half_joint == "shoulder_flexors_r"
    tl = run.timeline
    after = tl.time > on.time_s
    assert all(c.startswith("whole body: shoulder_flexors_r") for c in np.array(tl.case)[after])
    assert tl.residuals[after, 1].max() < 1e-4  # the line kept
    assert tl.residuals[after, 2].max() > 0.05  # the dot given up
    k = int(np.flatnonzero(tl.time == on.time_s)[0])
    load = tl.load[:, [h.name for h in problem.body.half_joints].index("shoulder_flexors_r")]
    assert load[after].max() < load[k]  # the tired group carries less from then on


def test_the_load_bound_is_the_owner_load_gradient_by_finite_differences() -> None:
    """The whole-body adjustment's bound aᵀq ≤ aᵀq₀ on the owner's load [%MVC]: ``a`` is the
    unit gradient of that load, here against central differences of the torque model's."""
    from casadi_posture import simulation

    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml")
    built = simulation._built(problem, 2)
    names = [h.name for h in problem.body.half_joints]
    rng = np.random.default_rng(7)
    for owner in ("elbow_flexors_r", "shoulder_flexors_r", "lumbar_extensors"):
        k = names.index(owner)
        q = problem.posture + rng.uniform(-0.05, 0.05, problem.body.n)
        inequality, load = built.whole_body.bound(q, k)
        assert load == pytest.approx(built.torque_model.evaluate(q).load_pct_mvc[k], rel=1e-12)
        h = 1e-6
        difference = np.array(
            [
                built.torque_model.evaluate(q + h * e).load_pct_mvc[k]
                - built.torque_model.evaluate(q - h * e).load_pct_mvc[k]
                for e in np.eye(problem.body.n)
            ]
        ) / (2 * h)
        np.testing.assert_allclose(inequality.a, difference / np.linalg.norm(difference), atol=1e-7)
        assert inequality.b == pytest.approx(float(inequality.a @ q), rel=1e-12)


def test_the_strategy_is_named_only_where_it_acts() -> None:
    """The wall hold's whole-body adjustment ignores fatigue.strategy: when the shoulder
    flexors take the constraint, the event says what acts (the whole-body adjustment bounds
    their load), not "passive strategy on shoulder_flexion_r", and summary.json's
    ``strategy`` and ``r_min`` are null, as ``fatigue_weight`` is under the paper's
    adjustment; there the strategy acts, and is named."""
    from dataclasses import replace

    from casadi_posture import simulation
    from casadi_posture.adjustment.constraint import FatigueConstraint
    from casadi_posture.output.results import summary

    sets = {"fatigue.strategy": "passive", "simulation.duration_s": 1.0}
    problem = cp.load(PROBLEMS / "standing_wall_horizontal.toml", sets)
    settings = simulation.constraint_settings(problem)
    assert settings.adjustment == "whole_body" and settings.keep_levels == 2
    built = simulation._built(problem, settings.keep_levels)
    names = [h.name for h in problem.body.half_joints]
    levels = np.zeros(len(names))
    levels[names.index("shoulder_flexors_r")] = settings.fatigue_threshold
    weight = settings.fatigue_weight
    whole = f"whole-body adjustment (levels 1-2 kept, effort weighed by 1 + {weight:g}·F)"
    for adjustment, whole_body, detail in (
        ("whole_body", built.whole_body, f"{whole}: its load bounded"),
        ("paper", None, "passive strategy on shoulder_flexion_r"),
    ):
        chosen = replace(settings, adjustment=adjustment)
        constraint = FatigueConstraint(problem.body, problem.passive, chosen, whole_body=whole_body)
        on = [e for e in constraint.update(levels, 10.0) if e.kind == "constraint_on"]
        assert [(e.half_joint, e.detail) for e in on] == [("shoulder_flexors_r", detail)]
    report = summary(cp.simulate(problem).result)
    assert (report["adjustment"], report["strategy"], report["r_min"]) == ("whole_body", None, None)
    paper = cp.load(PROBLEMS / "holding_m45.toml", {"fatigue.strategy": "passive"})
    report = summary(cp.simulate(paper.with_overrides({"simulation.duration_s": 1.0})).result)
    assert (report["adjustment"], report["strategy"], report["r_min"]) == ("paper", "passive", 0.9)
