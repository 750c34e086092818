"""casadi-posture design --objective compression: the NLP's measures are the low-back
model's compression, the answer is no worse than the start nor than any shelf height
solved alone, its numbers are LowBackModel.evaluate's, and a body without a lumbar joint
is refused with exit 2."""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS

from casadi_posture import static
from casadi_posture.biomech.low_back import LowBackModel
from casadi_posture.cli import main
from casadi_posture.problem import load_problem
from casadi_posture.workplace_design import Design, design
from casadi_posture.workplace_design.nlp import _measures

SHELF = PROBLEMS / "standing_shelf_box.toml"
HANDS = ("tasks[2].target_m[2]", "tasks[3].target_m[2]")  # both hands at the shelf's height
TIED = ",".join(HANDS)
BOUNDS = (1.0, 1.6)  # [m]
GRID = np.linspace(1.05, 1.55, 5)  # shelf heights the IK reaches [m]


@cache
def shelf_design() -> Design:
    return design(load_problem(SHELF), {TIED: BOUNDS}, "compression")


def _model(answer: Design) -> LowBackModel:
    problem = answer.problem
    return LowBackModel(problem.body, problem.loads)


def test_the_measures_are_the_models_compression() -> None:
    """The NLP's two smooth rows (one per muscle): their smallest is −compression [N] of
    LowBackModel.evaluate at postures that bend the trunk forward and back (the erector
    and the rectus abdominis branch)."""
    problem = load_problem(SHELF)
    body, torques = problem.body, problem.torque_model()
    measures, limits = _measures(problem, torques, "compression")
    assert measures.numel() == 2 and limits.numel() == 0
    function = ca.Function("rows", [body.q, torques.p], [measures])
    model = LowBackModel(body, problem.loads)
    rng = np.random.default_rng(7)
    signs = set()
    for _ in range(40):
        q = body.lower + (body.upper - body.lower) * rng.random(body.n)
        expected = model.evaluate(q)
        got = -float(np.min(np.asarray(function(q, model.default_loads))))
        assert got == pytest.approx(expected.compression, rel=1e-12, abs=1e-9)
        signs.add(math.copysign(1.0, expected.sagittal_moment))
    assert signs == {-1.0, 1.0}


def test_the_answer_beats_the_start_and_every_height_alone() -> None:
    """The best compression is at most the start's, at most the IK's at five shelf heights
    (postures the NLP could take: the IK keeps the trunk straight, as the NLP must) and at
    most the NLP's own at each height held fixed (bounds ±0.5 mm about it)."""
    answer = shelf_design()
    assert answer.success, answer.status
    assert answer.kept_residual <= 1e-4
    assert answer.best.value <= answer.start.value
    lumbar = [answer.problem.body.index[n] for n in ("lumbar_bending", "lumbar_rotation")]
    for z in GRID:
        at = load_problem(SHELF, dict.fromkeys(HANDS, float(z)))
        ik = static.solve(at)
        assert all(level.achieved for level in ik.levels[:2])
        np.testing.assert_allclose(ik.torques.q[lumbar], 0.0, atol=1e-6)
        assert answer.best.value <= ik.low_back.compression + 1e-6
        fixed = design(at, {TIED: (z - 5e-4, z + 5e-4)}, "compression")
        assert fixed.success, fixed.status
        assert answer.best.value <= fixed.best.value + 1.0  # [N]: a local method's slack
    # the trunk is not bent sideways or twisted to hide the load from the sagittal model
    np.testing.assert_allclose(answer.best_answer.torques.q[lumbar], 0.0, atol=1e-9)


def test_the_reported_compressions_are_the_models() -> None:
    answer = shelf_design()
    model = _model(answer)
    for score, posture in (
        (answer.start, answer.start_answer),
        (answer.best, answer.best_answer),
        (answer.check, answer.check_answer),
    ):
        expected = model.evaluate(posture.torques.q).compression
        assert score.value == pytest.approx(expected, rel=1e-12)
    assert answer.gain == pytest.approx(answer.start.value - answer.check.value)
    assert answer.nlp_gain == pytest.approx(answer.start.value - answer.best.value)
    # the re-solve is the IK at the best height, solved alone
    at = load_problem(SHELF, dict.fromkeys(HANDS, answer.best_m[0]))
    assert answer.check.value == pytest.approx(static.solve(at).low_back.compression, rel=1e-9)


def test_a_body_without_a_lumbar_joint_is_refused_with_exit_2() -> None:
    path = PROBLEMS / "holding_horizontal.toml"
    args = ["design", str(path), "--objective", "compression"]
    args += ["--free", "tasks[0].point_m[2],tasks[1].target_m[2]=-0.5:0.1"]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert str(path) in lines[0] and "--objective = 'compression'" in lines[0]
    assert "lumbar joint" in lines[0]
    assert "Traceback" not in result.output


def test_cli_json_and_figure(tmp_path: Path) -> None:
    out = tmp_path / "design"
    args = ["design", str(SHELF), "--objective", "compression", "--free", f"{TIED}=1.0:1.6"]
    result = CliRunner().invoke(main, [*args, "--json", "--out", str(out)])
    assert result.exit_code == 1, result.output  # flagged: the re-solve keeps comfort
    data = json.loads(result.stdout)
    assert data["objective"] == "compression"
    assert data["low_back"]["niosh_limits_N"] == {"design": 3400.0, "upper": 6400.0}
    for part in ("start", "best", "check"):
        value = data[part]["compression_N"]
        assert math.isfinite(value) and value > 0
        assert data[part]["above_niosh_design_limit"] is (value > 3400.0)
        assert data[part]["above_niosh_upper_limit"] is (value > 6400.0)
    assert data["gain"]["unit"] == "N"
    start, check = data["start"]["compression_N"], data["check"]["compression_N"]
    assert data["gain"]["absolute"] == pytest.approx(start - check)
    assert data["gain"]["ratio"] == pytest.approx(check / start)
    assert data["check"]["tolerance"] == "1 % of the NLP's compression"
    written = json.loads((out / "design.json").read_text())
    held = [s["compression_N"] for s in written["sweep"] if s["task_kept"]]
    assert len(written["sweep"]) == 15 and len(held) >= 10
    assert all(math.isfinite(v) for v in held)
    assert data["best"]["compression_N"] <= min(held)  # no grid height beats the NLP
    assert (out / "design.png").stat().st_size > 0
    table = CliRunner().invoke(main, args)
    assert "L5/S1 compression (N)" in table.output
    assert f"reduction (IK re-solved at the design): {start - check:+.1f} N" in table.output
    assert "below the design limit 3400 N" in table.output


def test_two_free_quantities_draw_the_compression(tmp_path: Path) -> None:
    """Shelf height and distance free: the figure is the compression's bars; moving the
    box closer lowers the compression below the height alone's."""
    out = tmp_path / "design"
    args = ["design", str(SHELF), "--objective", "compression", "--free", f"{TIED}=1.0:1.6"]
    args += ["--free", "tasks[2].target_m[0],tasks[3].target_m[0]=0.5:0.7", "--json"]
    result = CliRunner().invoke(main, [*args, "--out", str(out)])
    data = json.loads(result.stdout)
    assert data["ipopt"]["success"], data["ipopt"]
    assert data["best"]["compression_N"] < shelf_design().best.value
    assert data["free"][1]["best_m"] < 0.62  # the box comes closer
    assert "sweep" not in json.loads((out / "design.json").read_text())
    assert (out / "design.png").stat().st_size > 0
