"""Sensitivities by AD against central finite differences of the same outcome, computed
through the problem's own pipeline (the file re-read with the input changed, the IK re-solved,
the loads and endurances of ``static``), and against closed forms."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

import casadi_posture as cp
from casadi_posture.biomech.fatigue import fatigue_model
from casadi_posture.cli import main
from casadi_posture.problem import Problem, load_problem, problem_from_data
from casadi_posture.sensitivity_analysis.analysis import Sensitivity, sensitivity
from casadi_posture.sensitivity_analysis.parametric import Input, ParametricProblem
from casadi_posture.sensitivity_analysis.posture import posture_derivative
from casadi_posture.static import group_loads
from casadi_posture.static import solve as solve_static

RELATIVE = 1e-5


def _perturbed(problem: Problem, item: Input, delta: float) -> Problem:
    """``problem`` with one input changed by ``delta`` (in the input's unit): through the
    problem file's key, or for shipped coefficients through the model objects."""
    if item.kind == "passive":
        _, dof, _, name = item.key.split(".")
        model = problem.passive[dof]
        value = item.value + delta
        changed = replace(model, **{name: math.radians(value) if name in ("q1", "q2") else value})
        return replace(problem, passive={**problem.passive, dof: changed})
    if item.kind == "endurance":
        endurance = problem.fatigue.endurance
        if hasattr(endurance, "table"):  # coefficients per region (frey_law_avin)
            record = endurance.table[item.key]
            table = {**endurance.table, item.key: replace(record, value=record.value + delta)}
            endurance = replace(endurance, table=table)
        else:
            name = item.key.rsplit(".", 1)[1]
            record = getattr(endurance, name)
            endurance = replace(endurance, **{name: replace(record, value=record.value + delta)})
        regions = [h.region for h in problem.body.half_joints]
        fatigue = fatigue_model(
            problem.spec.fatigue.recovery_law,
            regions=regions,
            endurance=endurance,
            recovery_threshold_pct_mvc=problem.spec.fatigue.load_threshold_pct_mvc,
        )
        return replace(problem, fatigue=fatigue)
    key, value = item.key, item.value + delta
    if item.kind == "load" and not key.endswith("mass_kg"):  # a whole vector: files may omit it
        head, index = key[:-1].rsplit("[", 1)
        load = problem.loads[int(head.split("[")[1].split("]")[0])]
        vector = list(load.force if "force" in head else load.moment)
        vector[int(index)] += delta
        key, value = head, vector
    return problem_from_data(problem.data, problem.path, {**problem.overrides, key: value})


def _outcome(problem: Problem, group: str) -> tuple[float, float]:
    """The group's load [%MVC] and endurance [s] at the solved (and polished) posture."""
    answer = solve_static(problem)
    graph = ParametricProblem(problem, problem.hierarchy(), symbolic=False)
    posture = posture_derivative(graph, answer.torques.q, [lv.achieved for lv in answer.levels])
    loads = group_loads(problem, problem.torque_model().evaluate(posture.q))
    found = next(g for g in loads if g.name == group)
    return found.load_pct_mvc, found.endurance_s


def _check(problem: Problem, result: Sensitivity, keys: list[str] | None = None) -> int:
    """Every input (or those of ``keys``): AD = central FD to ``RELATIVE``, for the limiting
    group's load and the task's endurance. Returns how many were checked."""
    k = result.groups.index(result.limiting)
    checked = 0
    for j, item in enumerate(result.inputs):
        if keys is not None and item.key not in keys:
            continue
        h = 1e-4 * max(abs(item.value), 1.0)
        load_plus, endurance_plus = _outcome(_perturbed(problem, item, h), result.limiting)
        load_minus, endurance_minus = _outcome(_perturbed(problem, item, -h), result.limiting)
        pairs = (
            (result.d_load[k, j], (load_plus - load_minus) / (2 * h), result.load_pct_mvc[k]),
            (
                result.d_task[j],
                (endurance_plus - endurance_minus) / (2 * h),
                result.task_endurance_s,
            ),
        )
        scale = max(abs(item.value), 1.0)
        for ad, fd, outcome in pairs:
            floor = 1e-7 * abs(outcome) / scale
            assert abs(ad - fd) <= RELATIVE * max(abs(ad), abs(fd)) + floor, (item.key, ad, fd)
        checked += 1
    return checked


def test_every_input_of_the_2dof_arm_against_finite_differences() -> None:
    problem = cp.load("problems/holding_horizontal.toml")
    result = sensitivity(problem)
    assert result.limiting == "shoulder_flexors" and not result.flags
    kinds = {item.kind for item in result.inputs}
    assert kinds == {"load", "target", "body", "strength", "passive", "endurance"}
    assert _check(problem, result) == len(result.inputs) == 35
    assert "tasks[0].elevation_deg" in {item.key for item in result.inputs}
    assert "tasks[0].azimuth_deg" in result.left_out  # the arm moves in one plane


def test_a_minimised_level_an_unreachable_dot_against_finite_differences() -> None:
    """The dot 5 cm above a horizontal line of higher priority: level 2 is not achieved and
    minimised, its multipliers carry the line's curvature."""
    problem = cp.load("problems/holding_horizontal.toml", {"tasks[1].target_m": [0.3, 0.0, -0.2]})
    result = sensitivity(problem)
    assert result.posture.minimised == 2 and result.posture.kept == (1,)
    keys = ["tasks[0].point_m[2]", "tasks[1].target_m[0]", "tasks[1].target_m[2]"]
    keys += ["tasks[0].elevation_deg", "loads[0].mass_kg", "body.stature_m"]
    assert _check(problem, result, keys) == 6


@pytest.mark.parametrize(
    ("name", "group"),
    [
        ("seated_assembly", "shoulder_external_rotators_r"),
        ("standing_shelf_box", "lumbar_extensors"),
    ],
)
def test_a_measured_strength_s_scale_against_finite_differences(name: str, group: str) -> None:
    """The seated worker's external rotators and the shelf's trunk extensors, shipped
    measured values the comfort measure does not divide by: their input is the file's
    strength_scale, and the group's own load follows it as a finite difference of the
    re-solved problem does."""
    problem = cp.load(f"problems/{name}.toml")
    result = sensitivity(problem)
    j, item = next(
        (j, item)
        for j, item in enumerate(result.inputs)
        if item.key == f"body.half_joints.{group}.strength_scale"
    )
    assert item.value == 1.0 and item.unit == "1"
    k = result.groups.index(group)
    h = 1e-4
    plus = _outcome(_perturbed(problem, item, h), group)[0]
    minus = _outcome(_perturbed(problem, item, -h), group)[0]
    fd = (plus - minus) / (2 * h)
    assert result.d_load[k, j] == pytest.approx(fd, rel=RELATIVE, abs=1e-7)
    assert result.d_load[k, j] < -0.01 * result.load_pct_mvc[k]


@pytest.mark.slow
def test_the_standing_body_against_finite_differences() -> None:
    """29 DOF, four levels (feet, balance and the protocol's plane, line, dot, comfort): a
    sample of every kind."""
    problem = cp.load("problems/standing_wall_horizontal.toml")
    result = sensitivity(problem)
    assert result.posture.dq is not None and not result.flags
    keys = [
        "body.stature_m",
        "body.mass_kg",
        "loads[0].mass_kg",
        "loads[0].force_N[0]",
        "tasks[3].point_m[2]",
        "tasks[3].elevation_deg",
        "tasks[3].azimuth_deg",
        "tasks[4].target_m[0]",
        "tasks[2].reference_deg.lumbar_rotation",
        "posture_deg.shoulder_flexion_r",
        "body.half_joints.shoulder_flexors_r.strength_scale",
        "joints.shoulder_flexion_r.passive.k3",
        "endurance.frey_law_avin.shoulder.b1",
    ]
    assert _check(problem, result, keys) == len(keys)


@pytest.mark.slow
def test_an_orientation_tasks_angles_against_finite_differences() -> None:
    """The drill held pointing up (roll, pitch, yaw 0, 180, 0 deg) on the 29-DOF body."""
    problem = cp.load("problems/standing_overhead_drill.toml")
    result = sensitivity(problem)
    assert result.posture.dq is not None and not result.flags
    assert list(result.left_out) == ["tasks[4]"]  # the comfort level's neutral and weights
    keys = [f"tasks[3].target_rpy_deg[{k}]" for k in range(3)]
    assert _check(problem, result, keys) == len(keys)


@pytest.mark.slow
def test_the_seat_height_of_the_upper_body_against_finite_differences() -> None:
    problem = cp.load("problems/seated_assembly.toml")
    result = sensitivity(problem)
    assert "body.hip_height_m" in [i.key for i in result.inputs]
    assert _check(problem, result, ["body.hip_height_m", "body.stature_m"]) == 2


def test_elasticities_of_manenica_have_closed_forms() -> None:
    """E = 60·exp(a − b·T) with T = 100·τ/st and τ not depending on a, b or st: the elasticity
    is a for a, −b·T for b, and b·T for the limiting group's strength (here its ratio to the
    body's elbow flexion, in proportion to it)."""
    result = sensitivity(cp.load("problems/holding_horizontal.toml"))
    rows = {r["key"]: r for r in result.ranked()}
    load = result.load_pct_mvc[result.groups.index("shoulder_flexors")]
    a = rows["endurance.manenica.a"]
    b = rows["endurance.manenica.b"]
    assert a["endurance_elasticity"] == pytest.approx(a["value"], rel=1e-12)
    assert b["endurance_elasticity"] == pytest.approx(-b["value"] * load, rel=1e-12)
    strength = rows["body.half_joints.shoulder_flexors.strength_ratio"]
    assert strength["endurance_elasticity"] == pytest.approx(b["value"] * load, rel=1e-10)
    assert strength["load_elasticity"] == pytest.approx(-1.0, rel=1e-10)
    assert rows["loads[0].force_N[0]"]["endurance_elasticity"] is None  # the input is 0


def test_a_posture_the_tasks_leave_free_is_flagged() -> None:
    """Without its comfort level the standing body's trunk and legs are undetermined: the
    derivatives hold the posture fixed and say so. With it, a symmetric two-hand hold is
    determined and not flagged."""
    problem = cp.load("problems/standing_shelf_box.toml")
    tasks = [t for t in problem.data["tasks"] if t["kind"] != "comfort"]
    free = problem_from_data({**problem.data, "tasks": tasks}, problem.path)
    result = sensitivity(free)
    assert result.posture.dq is None
    assert any("hold the posture fixed" in f for f in result.flags)
    determined = sensitivity(problem)
    assert determined.posture.dq is not None
    assert not any("hold the posture fixed" in f for f in determined.flags)
    assert [f for f in determined.flags if "ties with" in f]  # the two shoulders, one load


def test_the_command_writes_its_table_json_csv_and_tornado(tmp_path) -> None:
    out = tmp_path / "sens"
    done = CliRunner().invoke(
        main,
        ["sensitivity", "problems/holding_horizontal.toml", "--kind", "load", "--out", str(out)],
    )
    assert done.exit_code == 0, done.output
    assert "loads[0].mass_kg" in done.output and "body.stature_m" not in done.output
    data = json.loads((out / "sensitivity.json").read_text())
    assert data["task"]["limiting"] == "shoulder_flexors"
    assert len(data["inputs"]) == 35 and len(data["groups"]) == 4
    values = [r["d_endurance_min_per_unit"] for r in data["task"]["ranked"]]
    assert all(np.isfinite(values))
    assert (out / "tornado.png").stat().st_size > 0
    assert (out / "sensitivity.csv").read_text().startswith("key,kind,value,unit")


def test_the_command_exits_1_on_a_flagged_answer() -> None:
    done = CliRunner().invoke(
        main,
        [
            "sensitivity",
            "problems/holding_horizontal.toml",
            "--set",
            "tasks[0].point_m=[0.3, 0, -2.0]",
        ],
    )
    assert done.exit_code == 1
    assert "FLAGGED" in done.output


def test_an_ik_answer_that_is_not_a_solution_is_held_fixed_and_keeps_its_own_numbers() -> None:
    """1000 kg on the seated assembly: the nullspace solver stalls, and polishing its answer
    moves a wrist by 8°; the derivatives are those of the answer's own posture (held fixed,
    flagged), and its compression is the static answer's (it was an internal error)."""
    problem = load_problem(PROBLEMS / "seated_assembly.toml", {"loads[0].mass_kg": 1000.0})
    result = sensitivity(problem)
    answer = solve_static(problem, None)
    assert not answer.ik.success
    assert result.compression == pytest.approx(answer.low_back.compression, rel=1e-12)
    assert np.array_equal(result.posture.q, answer.torques.q)
    held = [f for f in result.flags if f.startswith("derivatives hold the posture fixed")]
    assert held == [
        "derivatives hold the posture fixed: the IK's answer is not a solution (polishing it "
        "moved wrist_flexion_l by 8.01°)"
    ]
