"""Bodies described in problem files (``body.tree``): the built-in models are such trees,
a file's tree reproduces them exactly, and a faulty tree is refused naming its key."""

from __future__ import annotations

import copy
import tomllib
from typing import Any

import numpy as np
import pytest
from conftest import PROBLEMS

import casadi_posture as cp
from casadi_posture.body.models import MODELS
from casadi_posture.body.tree import REGIONS
from casadi_posture.data.parameters import load
from casadi_posture.errors import ProblemError
from casadi_posture.problem import problem_from_data
from casadi_posture.simulation import simulate


def _as_tree(name: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """A shipped problem's data, and the same problem with its built-in body replaced by the
    tree ``describe`` prints, every strength written out."""
    path = PROBLEMS / name
    data = tomllib.loads(path.read_text())
    problem = cp.load(path)
    described = cp.describe(problem)
    dofs = copy.deepcopy(described["dofs"])
    for dof in dofs:
        for side in ("positive", "negative"):
            for key in ("strength_ratio", "strength_scale", "strength_curve"):
                dof[side].pop(key, None)  # the group's strength, written out as a value
            dof[side]["strength_Nm"] = problem.strength[dof[side]["name"]].value
    tree = {"name": "my_arm", "dofs": dofs}
    tree |= {k: described[k] for k in ("segments", "landmarks")}
    own = copy.deepcopy(data)
    own["body"] = {"tree": tree}
    return data, own


def test_a_file_tree_reproduces_the_sagittal_arm_torques_solve_and_simulation() -> None:
    data, own = _as_tree("holding_m45.toml")
    builtin, mine = problem_from_data(data), problem_from_data(own)
    assert mine.body.name == "my_arm" and mine.body.n == builtin.body.n == 2
    rng = np.random.default_rng(3)
    for q in rng.uniform(builtin.body.lower, builtin.body.upper, size=(6, 2)):
        a, b = builtin.torque_model().evaluate(q), mine.torque_model().evaluate(q)
        for field in ("external", "passive", "active", "load_pct_mvc"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), field
    for solver in ("lexicographic", "nullspace"):
        assert np.array_equal(cp.solve(builtin, solver).ik.q, cp.solve(mine, solver).ik.q)
    short = {"simulation.duration_s": 300.0}
    a = simulate(problem_from_data(data, overrides=short))
    b = simulate(problem_from_data(own, overrides=short))
    assert np.array_equal(a.timeline.q, b.timeline.q)
    assert np.array_equal(a.timeline.fatigue, b.timeline.fatigue)
    assert a.events == b.events and any(e.kind == "constraint_on" for e in a.events)


def _tree_problem(**changes: Any) -> dict[str, Any]:
    """A one-DOF pendulum of the file's own, with ``changes`` merged into its DOF."""
    dof = {
        "name": "swing",
        "origin_m": [0.0, 0.0, 0.0],
        "axis": [0.0, 1.0, 0.0],
        "range_deg": [-90.0, 90.0],
        "positive": {"name": "pushers", "strength_Nm": 40.0, "region": "hip"},
        "negative": {"name": "pullers", "strength_Nm": 30.0},
    } | changes
    return {
        "body": {
            "tree": {
                "dofs": [dof],
                "segments": [
                    {"name": "rod", "dof": "swing", "mass_kg": 2.0, "com_m": [0, 0, -0.5]}
                ],
                "landmarks": [{"name": "tip", "dof": "swing", "position_m": [0.0, 0.0, -1.0]}],
            }
        },
        "posture_deg": {"swing": 30.0},
        "loads": [{"name": "bag", "at": "tip", "mass_kg": 1.0}],
    }


def test_a_pendulum_of_the_files_own_matches_a_hand_calculation() -> None:
    problem = problem_from_data(_tree_problem())
    torques = cp.torques(problem)
    # τe = -g·sin(30°)·(2 kg·0.5 m + 1 kg·1 m) about +y: gravity pulls the swing back to 0
    expected = -9.81 * np.sin(np.radians(30.0)) * (2.0 * 0.5 + 1.0 * 1.0)
    assert torques.torques.external[0] == pytest.approx(expected, rel=1e-12)
    records = {p.name: p for p in problem.parameters}
    assert records["strength.pushers"].value == 40.0
    assert records["joints.swing.passive.limit_torque.limit"].value == 5.0
    assert records["joints.swing.passive.q1"].value == -90.0  # anchored at the range
    assert records["joints.swing.passive.q2"].value == 90.0


def test_a_region_without_data_takes_the_general_endurance_fit_and_says_so() -> None:
    data = _tree_problem() | {"fatigue": {"endurance": "frey_law_avin"}}
    records = {p.name: p for p in problem_from_data(data).parameters}
    assert "no fit for a region named 'hip'" in records["endurance.frey_law_avin.hip.b0"].source
    assert "endurance.frey_law_avin.general.b1" in records  # the pullers' default region


def test_the_regions_are_those_with_endurance_data_and_those_the_built_in_bodies_use() -> None:
    fitted = {name.split(".")[2] for name in load("endurance") if name.count(".") == 3}
    bodies = {(p := cp.load(f)).spec.body.model: p.body for f in PROBLEMS.glob("*.toml")}
    used = {h.region for body in bodies.values() for h in body.half_joints}
    assert set(MODELS) <= set(bodies)  # every built-in body
    assert fitted == set(REGIONS) - {"hip"}
    assert used <= set(REGIONS) and "hip" in used


@pytest.mark.parametrize(
    ("change", "key", "expected"),
    [
        ({"parent": "nowhere"}, "body.tree.dofs[0].parent", "listed before it"),
        ({"axis": [0.0, 0.0, 0.0]}, "body.tree.dofs[0].axis", "non-zero"),
        ({"range_deg": [10.0, -10.0]}, "body.tree.dofs[0].range_deg", "min < max"),
        (
            {"negative": {"name": "pushers", "strength_Nm": 3.0}},
            "dofs[0].negative.name",
            "no other",
        ),
        ({"negative": {"name": "toe_curlers"}}, "dofs[0].negative.strength_Nm", "shipped defaults"),
        ({"passive": {"model": "gymnast_fit"}}, "dofs[0].passive.model", "fitted only for"),
        ({"origin_m": [0.0, 0.0, 150.0]}, "body.tree.dofs[0].origin_m[2]", "unit slip"),
        (
            {"positive": {"name": "pushers", "strength_Nm": 40.0, "region": "moon"}},
            "body.tree.dofs[0].positive.region = 'moon'",
            "a joint region: one of ['general', 'shoulder', 'elbow', 'hand', 'trunk', 'hip', "
            "'knee', 'ankle']",
        ),
    ],
)
def test_a_faulty_tree_is_refused_naming_the_key(change: dict, key: str, expected: str) -> None:
    with pytest.raises(ProblemError) as caught:
        problem_from_data(_tree_problem(**change), "pendulum.toml")
    message = str(caught.value)
    assert "pendulum.toml" in message and key in message and expected in message


def test_tree_references_and_sources_are_checked() -> None:
    data = _tree_problem()
    data["body"]["tree"]["segments"][0]["dof"] = "elbow"
    with pytest.raises(ProblemError, match=r"body.tree.segments\[0\].dof.*swing"):
        problem_from_data(data)
    data = _tree_problem()
    data["body"]["model"] = "sagittal_arm"
    with pytest.raises(ProblemError, match="exactly one of model"):
        problem_from_data(data)
    data = _tree_problem()
    data["body"]["half_joints"] = {"pushers": {"strength_Nm": 5.0}}
    with pytest.raises(ProblemError, match="change a tree in the tree"):
        problem_from_data(data)
    data = _tree_problem()
    data["loads"][0]["at"] = "wrist"
    with pytest.raises(ProblemError, match=r"loads\[0\].at.*tip"):
        problem_from_data(data)


def test_describe_prints_a_tree_that_loads_back_to_the_same_body() -> None:
    path = PROBLEMS.parent / "benchmarks" / "problems" / "humanoid_42.toml"
    problem = cp.load(path)
    described = cp.describe(problem)
    data = tomllib.loads(path.read_text())
    data["body"]["tree"] = {"name": described["model"]} | {
        k: described[k] for k in ("dofs", "segments", "landmarks")
    }
    again = problem_from_data(data)
    q = np.random.default_rng(5).uniform(problem.body.lower, problem.body.upper)
    a, b = problem.torque_model().evaluate(q), again.torque_model().evaluate(q)
    assert np.array_equal(a.external, b.external) and np.array_equal(a.active, b.active)


def test_the_documented_pendulum_loads_and_is_the_one_tested_here() -> None:
    text = (PROBLEMS.parent / "docs" / "problem-files.md").read_text()
    block = next(b for b in text.split("```toml\n")[1:] if b.startswith("[body.tree]"))
    documented = tomllib.loads(block.split("```")[0])
    problem = problem_from_data(documented | {"posture_deg": {"swing": 30.0}}, "docs")
    ours = _tree_problem()
    assert documented["body"]["tree"]["dofs"] == ours["body"]["tree"]["dofs"]
    assert problem.body.total_mass == 2.0
