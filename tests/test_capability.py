"""% of the population capable: the normal model against an independent normal CDF
(``statistics.NormalDist``) with the sources' numbers typed here, its behaviour in the load,
the task's share as the weakest group's, file-set strengths and the SDs' provenance."""

from __future__ import annotations

import json
import math
from pathlib import Path
from statistics import NormalDist

import casadi as ca
import numpy as np
import pytest
from click.testing import CliRunner

import casadi_posture as cp
from casadi_posture.biomech.capability import SEXES, share_capable
from casadi_posture.cli import main

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
G = 9.81
#: Harbo et al. 2012 elbow flexion, male: intercept, age, stature [m], mass [kg]; the Gymnast
#: shoulder-flexion ratio; our population CV (an estimate).
HARBO_MALE, HARBO_FEMALE = (-23.8, -0.13, 22.0, 0.51), (6.9, -0.13, 9.0, 0.18)
#: The shoulder flexors' ratio to Harbo elbow flexion at 0° (89.9 / 48.48 N·m), the curve's
#: fraction at 60° of flexion (on the straight line 1 → 0.7631 → 0.5261 at 0°, 45°, 90°) and
#: the estimated CV.
SHOULDER_FLEXION_RATIO, AT_60_DEG, CV = 1.8544, 0.7631 + (0.5261 - 0.7631) / 3, 0.28


def _above(mean: float, sd: float, required: float) -> float:
    """Share [%] of N(mean, sd²) at or above ``required``, by the standard library."""
    return 100.0 * (1.0 - NormalDist(mean, sd).cdf(required))


def _harbo(c: tuple[float, float, float, float], age: float, h: float, m: float) -> float:
    return c[0] + c[1] * age + c[2] * h + c[3] * m


@pytest.fixture(scope="module")
def standing() -> cp.StaticAnswer:
    return cp.torques(cp.load(PROBLEMS / "standing_shelf_box.toml"))


def _group(answer: cp.StaticAnswer, name: str) -> dict:
    return next(g for g in answer.capable_groups() if g["name"] == name)


def test_anderson_group_by_hand(standing: cp.StaticAnswer) -> None:
    """Right hip extensors of the 30-year-old reference male: Anderson 2007 young adults'
    c1 0.161 (men), 0.181 (women) times m·g·h and the age factor (men 1 − 0.0015·5, women 1
    before 40 y); CV the root mean square of the young and middle-aged rows' SD/c1 (men
    0.049/0.161 and 0.043/0.171, women 0.047/0.181 and 0.032/0.140)."""
    body = standing.problem.spec.body
    mgh = body.mass_kg * G * body.stature_m
    group = _group(standing, "hip_extensors_r")
    tau = group["torque_Nm"]
    assert tau > 1.0  # loaded, so the share is not the carries-nothing 100 %
    for sex, mean, rows in (
        ("male", 0.161 * mgh * 0.9925, ((0.161, 0.049), (0.171, 0.043))),
        ("female", 0.181 * mgh, ((0.181, 0.047), (0.140, 0.032))),
    ):
        cv = math.sqrt(sum((sd / c1) ** 2 for c1, sd in rows) / 2)
        assert group[f"mean_{sex}_Nm"] == pytest.approx(mean, rel=1e-12)
        assert group[f"capable_{sex}_pct"] == pytest.approx(_above(mean, cv * mean, tau), abs=1e-9)
    assert group["sd_status"] == "measured" and "Anderson 2007" in group["sd_source"]


def test_cv_estimate_group_by_hand(standing: cp.StaticAnswer) -> None:
    """Right shoulder flexors at 60° of flexion: Harbo elbow flexion of each sex at the male
    body's size × the ratio × the curve's fraction there, SD = 0.28 × mean (our
    estimate)."""
    body = standing.problem.spec.body
    size = (body.age_years, body.stature_m, body.mass_kg)
    group = _group(standing, "shoulder_flexors_r")
    tau = group["torque_Nm"]
    for sex, coefficients in (("male", HARBO_MALE), ("female", HARBO_FEMALE)):
        mean = _harbo(coefficients, *size) * SHOULDER_FLEXION_RATIO * AT_60_DEG
        assert group[f"mean_{sex}_Nm"] == pytest.approx(mean, rel=1e-4)
        shown = group[f"mean_{sex}_Nm"]
        assert group[f"capable_{sex}_pct"] == pytest.approx(
            _above(shown, CV * shown, tau), abs=1e-9
        )
    assert group["sd_status"] == "estimate" and "CV 0.28" in group["sd_source"]


def test_older_bodies_by_age() -> None:
    """A 70-year-old woman's knee extensors: the young c1 0.159 × (1 − 0.0086·30); a
    50-year-old man's: 0.163 × (1 − 0.0015·25); the same pooled CV at every age (women
    0.028/0.159 and 0.016/0.128, men 0.040/0.163 and 0.031/0.156), never the older row's."""
    for sex, age, c1, factor, rows in (
        ("female", 70.0, 0.159, 1 - 0.0086 * 30, ((0.159, 0.028), (0.128, 0.016))),
        ("male", 50.0, 0.163, 1 - 0.0015 * 25, ((0.163, 0.040), (0.156, 0.031))),
    ):
        problem = cp.load(
            PROBLEMS / "standing_shelf_box.toml", {"body.age_years": age, "body.sex": sex}
        )
        answer = cp.torques(problem)
        mgh = problem.spec.body.mass_kg * G * problem.spec.body.stature_m
        group = _group(answer, "knee_extensors_r")
        cv = math.sqrt(sum((sd / c) ** 2 for c, sd in rows) / 2)
        assert group[f"mean_{sex}_Nm"] == pytest.approx(c1 * factor * mgh, rel=1e-12)
        assert group[f"sd_{sex}_Nm"] == pytest.approx(cv * c1 * factor * mgh, rel=1e-12)


def test_share_decreases_with_the_load() -> None:
    """More mass at the wrist, a smaller share of both sexes, strictly."""
    shares = {sex: [] for sex in SEXES}
    for mass in (0.0, 1.0, 2.5, 5.0, 8.0):
        problem = cp.load(PROBLEMS / "holding_horizontal.toml", {"loads[0].mass_kg": mass})
        answer = cp.torques(problem)
        for sex in SEXES:
            shares[sex].append(answer.capable.share(sex))
    for sex in SEXES:
        assert np.all(np.diff(shares[sex]) < 0), shares[sex]
    assert shares["female"][-1] < shares["male"][-1]


def test_task_share_is_the_weakest_group(standing: cp.StaticAnswer) -> None:
    groups = standing.capable_groups()
    report = standing.capable_report()
    for sex in SEXES:
        values = [g[f"capable_{sex}_pct"] for g in groups]
        assert report[sex]["capable_pct"] == min(values) < 100.0
        assert report[sex]["weakest_group"] == groups[int(np.argmin(values))]["name"]
    unloaded = [g for g in groups if g["torque_Nm"] == 0.0]
    assert unloaded and all(g["capable_male_pct"] == 100.0 for g in unloaded)


def test_a_file_set_strength_is_the_body_s_sex_and_scales_to_the_other() -> None:
    """The file's 30 N·m is the mean of the body's sex (men); women's is 30 × the ratio of
    the sexes' Harbo elbow flexion at the body's size (the shipped defaults' ratio)."""
    problem = cp.load(
        PROBLEMS / "holding_m45.toml", {"body.half_joints.shoulder_flexors.strength_Nm": 30.0}
    )
    body = problem.spec.body
    size = (body.age_years, body.stature_m, body.mass_kg)
    answer = cp.torques(problem)
    group = _group(answer, "shoulder_flexors")
    tau = group["torque_Nm"]
    women = 30.0 * _harbo(HARBO_FEMALE, *size) / _harbo(HARBO_MALE, *size)
    for sex, mean in (("male", 30.0), ("female", women)):
        assert group[f"mean_{sex}_Nm"] == pytest.approx(mean, rel=1e-12)
        assert group[f"sd_{sex}_Nm"] == pytest.approx(CV * mean, rel=1e-12)
        assert group[f"capable_{sex}_pct"] == pytest.approx(_above(mean, CV * mean, tau), abs=1e-9)
    assert "body.half_joints.shoulder_flexors" in group["mean_source"]
    assert "the other sex by the ratio" in group["mean_source"]
    assert "strength.toml" in _group(answer, "elbow_flexors")["mean_source"]


def test_share_capable_on_floats_arrays_and_casadi() -> None:
    """One formula for floats, numpy arrays and CasADi expressions (an NLP maximises it); its
    derivative in the required torque is minus the normal density ×100, by AD."""
    mean, sd = 50.0, 14.0
    required = np.array([0.0, 20.0, 50.0, 80.0])
    expected = [_above(mean, sd, t) for t in required]
    assert share_capable(mean, sd, required) == pytest.approx(expected, abs=1e-12)
    assert [share_capable(mean, sd, float(t)) for t in required] == pytest.approx(expected)
    tau = ca.SX.sym("tau")
    share = share_capable(mean, sd, tau)
    f = ca.Function("f", [tau], [share, ca.jacobian(share, tau)])
    for t, want in zip(required, expected, strict=True):
        value, slope = (float(v) for v in f(t))
        assert value == pytest.approx(want, abs=1e-12)
        density = math.exp(-0.5 * ((t - mean) / sd) ** 2) / (sd * math.sqrt(2 * math.pi))
        assert slope == pytest.approx(-100.0 * density, rel=1e-9)


def test_cli_shows_the_columns_and_the_sd_sources() -> None:
    runner = CliRunner()
    problem = str(PROBLEMS / "holding_m45.toml")
    text = runner.invoke(main, ["torques", problem]).output
    assert "capable men (%)" in text and "capable women (%)" in text
    assert "capable of the task: 99.3 % of men (weakest: shoulder_flexors)" in text
    assert "population SDs: CV 0.28 × mean, our estimate, for every group" in text
    data = json.loads(runner.invoke(main, ["torques", problem, "--json"]).output)
    assert {g["sd_status"] for g in data["capable"]["half_joints"]} == {"estimate"}
    assert data["capable"]["female"]["weakest_group"] == "shoulder_flexors"


def test_whatif_rows_and_figure(tmp_path: Path) -> None:
    """A static what-if writes each case's task share (that of the solved start posture) to
    whatif.csv and draws it against the varied key; a simulated row has the same share."""
    problem = PROBLEMS / "holding_horizontal.toml"
    masses = [2.5, 7.5]
    report = cp.whatif(problem, {"loads[0].mass_kg": masses}, tmp_path / "w", static=True)
    rows = sorted(report.rows, key=lambda r: r["loads[0].mass_kg"])
    for row, mass in zip(rows, masses, strict=True):
        answer = cp.solve(cp.load(problem, {"loads[0].mass_kg": mass}))
        for sex in SEXES:
            assert row[f"capable_{sex}_pct"] == pytest.approx(answer.capable.share(sex), abs=1e-9)
    assert rows[1]["capable_female_pct"] < rows[0]["capable_female_pct"]
    header = (tmp_path / "w" / "whatif.csv").read_text().splitlines()[0].split(",")
    assert {"capable_male_pct", "capable_female_pct"} <= set(header)
    assert (tmp_path / "w" / "whatif_capable_pct_vs_loads_0_.mass_kg.png").exists()
    run = cp.simulate(cp.load(problem, {"simulation.duration_s": 2.0}))
    assert run.row()["capable_male_pct"] == pytest.approx(
        cp.solve(cp.load(problem)).capable.share("male"), abs=1e-6
    )


def test_edges_carries_nothing_and_no_strength() -> None:
    """τ = 0 counts as 100 % (not Φ(μ/σ) < 100); a population mean that is not positive (a
    regression outside its range) gives 0 % for any load, never a NaN."""
    from casadi_posture.biomech.capability import PopulationStrength, capability

    weak = PopulationStrength(
        "g",
        {"male": 10.0, "female": -2.0},
        {"male": 2.8, "female": -0.56},
        "test",
        "test",
        "estimate",
    )
    result = capability([weak, weak], [0.0, 5.0])
    assert result.groups[0].capable_pct == {"male": 100.0, "female": 100.0}
    assert result.groups[1].capable_pct["male"] == pytest.approx(_above(10.0, 2.8, 5.0))
    assert result.groups[1].capable_pct["female"] == 0.0
    assert result.share("female") == 0.0 and result.weakest("female").required == 5.0
