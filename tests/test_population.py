"""Virtual workers: drawn to ANSUR II's statistics and the shipped strength spreads."""

from __future__ import annotations

import numpy as np
import pytest

from casadi_posture.biomech.capability import strength_spread
from casadi_posture.people.sampling import MAX_WORKERS, draw_workers, group_correlation

GROUPS = ("shoulder_flexors", "elbow_flexors", "knee_extensors")
#: ANSUR II's raw data, as docs/population.md gives them: stature mean and SD [m], body
#: mass mean, SD and P5 / P50 / P95 [kg], and the correlation of stature with mass.
SURVEY = {
    "male": (1.7562, 0.0686, 85.52, 14.22, (64.4, 84.6, 110.7), 0.4689),
    "female": (1.6285, 0.0642, 67.76, 10.98, (51.3, 66.8, 87.1), 0.5335),
}


@pytest.fixture(scope="module")
def many() -> list:
    return draw_workers(20_000, ("male", "female"), GROUPS, seed=7)


@pytest.mark.parametrize("sex", ["male", "female"])
def test_the_workers_have_the_survey_s_stature_and_mass(many: list, sex: str) -> None:
    """20 000 of each sex: stature and mass means within 4 standard errors, SDs within 2 %,
    the mass percentiles within 1 kg (a lognormal mass: the survey's skew) and the
    correlation within 0.02."""
    workers = [w for w in many if w.sex == sex]
    stature = np.array([w.stature_m for w in workers])
    mass = np.array([w.mass_kg for w in workers])
    h_mean, h_sd, m_mean, m_sd, percentiles, r = SURVEY[sex]
    n = len(workers)
    assert abs(stature.mean() - h_mean) < 4 * h_sd / np.sqrt(n)
    assert abs(mass.mean() - m_mean) < 4 * m_sd / np.sqrt(n)
    assert stature.std() == pytest.approx(h_sd, rel=0.02)
    assert mass.std() == pytest.approx(m_sd, rel=0.02)
    np.testing.assert_allclose(np.percentile(mass, [5, 50, 95]), percentiles, atol=1.0)
    assert np.corrcoef(stature, mass)[0, 1] == pytest.approx(r, abs=0.02)


#: ANSUR II's subjects of 18 and over, as docs/population.md gives them: the mean and median
#: age in whole years, and the normal-score correlations of age with stature and ln mass.
SURVEY_AGES = {"male": (30.16, 28.0, -0.0026, 0.2691), "female": (28.95, 27.0, 0.0314, 0.2239)}


def _normal_scores(x: np.ndarray) -> np.ndarray:
    from statistics import NormalDist

    ranks = np.empty(x.size)
    ranks[np.argsort(x, kind="stable")] = np.arange(1, x.size + 1)
    return np.array([NormalDist().inv_cdf(p) for p in (ranks - 0.5) / x.size])


@pytest.mark.parametrize("sex", ["male", "female"])
def test_the_workers_have_the_survey_s_ages_and_their_correlations(many: list, sex: str) -> None:
    """20 000 of each sex: the whole years of their ages have the survey's mean (within 4
    standard errors) and median, every age lies in the survey's 18 to 58 (and the year
    after the last birthday), each year's share is the survey's within 4 standard errors,
    and the normal-score correlations of age with stature and ln mass are the survey's
    within 0.03."""
    from casadi_posture.people.sampling import ages

    workers = [w for w in many if w.sex == sex]
    age = np.array([w.age_years for w in workers])
    years = np.floor(age)
    mean, median, with_stature, with_mass = SURVEY_AGES[sex]
    assert abs(years.mean() - mean) < 4 * years.std() / np.sqrt(years.size)
    assert np.median(years) == median
    assert age.min() >= 18.0 and age.max() < 59.0
    first, share = ages(sex)
    drawn = np.bincount(years.astype(int) - first, minlength=share.size) / years.size
    error = np.sqrt(share * (1 - share) / years.size)
    assert (np.abs(drawn - share) <= 4 * error + 1e-4).all()
    scores = [
        _normal_scores(np.array(v))
        for v in ([w.stature_m for w in workers], np.log([w.mass_kg for w in workers]), age)
    ]
    assert np.corrcoef(scores[0], scores[2])[0, 1] == pytest.approx(with_stature, abs=0.03)
    assert np.corrcoef(scores[1], scores[2])[0, 1] == pytest.approx(with_mass, abs=0.03)


def test_an_age_s_quantile_falls_in_its_year() -> None:
    """The quantile at the top of a year's share is the end of that year; just above the
    share below it, its start; halfway through the share, its middle."""
    from casadi_posture.people.sampling import age_at, ages

    first, share = ages("female")
    cdf = np.cumsum(share)
    got = age_at("female", np.array([share[0] / 2, cdf[0], cdf[4] + 1e-12, cdf[4] + share[5] / 2]))
    np.testing.assert_allclose(got, [first + 0.5, first + 1.0, first + 5.0, first + 5.5], atol=1e-6)


def test_a_worker_s_age_weakens_their_strength_as_the_decline_says() -> None:
    """Two of the wall hold's workers, the same but for age: the older's knee extensors
    (Anderson 2007's young adults' strength) are weaker by the ratio of the shipped age
    decline's factors, and the elbow flexors by Harbo 2012's regression in age."""
    from dataclasses import replace
    from pathlib import Path

    from casadi_posture.biomech.strength import age_factor, elbow_flexion
    from casadi_posture.problem import load_problem
    from casadi_posture.runs.population import draw, worker_cases

    path = Path(__file__).resolve().parents[1] / "problems" / "standing_wall_horizontal.toml"
    problem = load_problem(path)
    worker = draw(problem, 1, ("female",), seed=1)[0]
    young, old = replace(worker, age_years=25.0), replace(worker, age_years=55.0)
    cases, _ = worker_cases(problem, path.read_text(), [young, old], None, False)
    assert [c.overrides["body.age_years"] for c in cases] == [25.0, 55.0]
    q = problem.posture
    strengths = [load_problem(path, c.overrides).torque_model().evaluate(q).strength for c in cases]
    names = [h.name for h in problem.body.half_joints]
    knee, elbow = names.index("knee_extensors_r"), names.index("elbow_flexors_r")
    ratio = age_factor("female", 55.0)[0] / age_factor("female", 25.0)[0]
    assert ratio < 1
    assert strengths[1][knee] / strengths[0][knee] == pytest.approx(ratio, rel=1e-9)
    size = (worker.stature_m, worker.mass_kg)
    harbo = elbow_flexion("female", *size, 55.0)[0] / elbow_flexion("female", *size, 25.0)[0]
    assert harbo < 1
    assert strengths[1][elbow] / strengths[0][elbow] == pytest.approx(harbo, rel=1e-3)


@pytest.mark.parametrize("sex", ["male", "female"])
def test_strength_factors_have_mean_1_the_group_spread_and_the_person_s_correlation(
    many: list, sex: str
) -> None:
    factors = np.array([[w.strength[g] for g in GROUPS] for w in many if w.sex == sex])
    np.testing.assert_allclose(factors.mean(axis=0), 1.0, atol=0.01)
    cv = [strength_spread(g)[0][sex] for g in GROUPS]
    np.testing.assert_allclose(factors.std(axis=0) / factors.mean(axis=0), cv, rtol=0.03)
    assert (factors > 0).all()
    logs = np.corrcoef(np.log(factors).T)
    off = logs[np.triu_indices(len(GROUPS), 1)]
    np.testing.assert_allclose(off, group_correlation(), atol=0.03)


def test_a_seed_gives_the_same_workers_and_each_sex_its_own_stream() -> None:
    both = draw_workers(50, ("male", "female"), GROUPS, seed=3)
    assert both == draw_workers(50, ("male", "female"), GROUPS, seed=3)
    men = draw_workers(50, ("male",), GROUPS, seed=3)
    assert men == [w for w in both if w.sex == "male"]
    assert draw_workers(50, ("male",), GROUPS, seed=4) != men
    assert [w.name for w in men[:2]] == ["male-0000", "male-0001"]


@pytest.mark.parametrize("correlation", [0.0, 1.0])
def test_the_group_correlation_can_be_set(correlation: float) -> None:
    workers = draw_workers(5000, ("female",), GROUPS, seed=1, correlation=correlation)
    logs = np.log([[w.strength[g] for g in GROUPS] for w in workers])
    assert np.corrcoef(logs.T)[0, 1] == pytest.approx(correlation, abs=0.04)


@pytest.mark.parametrize(
    ("n", "correlation"), [(0, None), (MAX_WORKERS + 1, None), (10, 1.5), (10, -0.1)]
)
def test_bad_sizes_and_correlations_are_refused(n: int, correlation: float | None) -> None:
    with pytest.raises(ValueError, match=r"n:|correlation:"):
        draw_workers(n, ("male",), GROUPS, seed=1, correlation=correlation)


def test_a_worker_s_strength_reaches_the_torque_model_as_a_problem_key() -> None:
    """The keys docs/population.md gives: a worker's sex, size and a group's factor set on
    a problem scale that group's strength by the factor at the worker's size."""
    import casadi_posture as cp

    worker = draw_workers(1, ("female",), ("shoulder_flexors",), seed=2)[0]
    body = {
        "body.sex": "female",
        "body.stature_m": worker.stature_m,
        "body.mass_kg": worker.mass_kg,
    }
    plain = cp.load("problems/standing_wall_horizontal.toml", body)
    factor = worker.strength["shoulder_flexors"]
    key = "body.half_joints.shoulder_flexors_r.strength_scale"
    scaled = cp.load("problems/standing_wall_horizontal.toml", {**body, key: factor})
    k = [h.name for h in plain.body.half_joints].index("shoulder_flexors_r")
    base = plain.torque_model().evaluate(plain.posture).strength
    got = scaled.torque_model().evaluate(scaled.posture).strength
    assert len(base) == len(plain.body.half_joints)
    assert got[k] == pytest.approx(factor * base[k], rel=1e-9)
    others = np.delete(np.arange(len(base)), k)
    np.testing.assert_allclose(got[others], base[others], rtol=1e-12)


def test_the_wilson_interval_matches_its_textbook_values() -> None:
    from casadi_posture.people.statistics import wilson

    np.testing.assert_allclose(wilson(5, 10), (0.2366, 0.7634), atol=1e-4)
    np.testing.assert_allclose(wilson(0, 10), (0.0, 0.2775), atol=1e-4)
    np.testing.assert_allclose(wilson(10, 10), (0.7225, 1.0), atol=1e-4)


ARM = "problems/holding_horizontal.toml"


def _population(tmp_path, *extra: str):
    from click.testing import CliRunner

    from casadi_posture.cli import main

    out = tmp_path / "pop"
    args = ["population", ARM, "--n", "3", "--out", str(out), "--set", "simulation.duration_s=90"]
    return CliRunner().invoke(main, [*args, *extra]), out


def test_a_population_run_reports_the_share_still_holding_from_its_workers_rows(
    tmp_path,
) -> None:
    """3 workers of each sex on the 2-DOF arm for 90 s: population.json's share at 1 min is
    the share of summary.csv's rows held at least 60 s, with its Wilson interval; at 2 min
    and later it is beyond the run. The same seed gives the same file; --resume runs
    nothing again; each worker's body is its draw."""
    import csv
    import json

    from casadi_posture.people.statistics import wilson

    result, out = _population(tmp_path)
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "population.json").read_text())
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert len(rows) == 6 and {r["status"] for r in rows} == {"ok"}
    workers = draw_workers(3, ("male", "female"), [], seed=1)
    for worker in workers:
        row = next(r for r in rows if r["case"] == worker.name)
        assert float(row["body.stature_m"]) == pytest.approx(worker.stature_m, abs=1e-4)
        assert row["body.sex"] == worker.sex
    for sex, data in summary["sexes"].items():
        mine = [r for r in rows if r["body.sex"] == sex]
        held = sum(float(r["task_held_s"]) >= 60.0 for r in mine)
        first = data["still_holding"][0]
        assert (first["minutes"], first["n"], first["held"]) == (1, 3, held)
        assert (first["low"], first["high"]) == pytest.approx(wilson(held, 3))
        assert all(s["share"] is None for s in data["still_holding"][1:])
    assert (out / "survival.png").exists() and (out / "held_vs_stature.png").exists()
    assert not (out / "cases" / "male-0000" / "timeline.csv").exists()  # rows only
    again, _ = _population(tmp_path, "--resume")
    assert again.exit_code == 0 and "0 run now, 6 already done" in again.output
    assert json.loads((out / "population.json").read_text()) == summary
    fresh, _ = _population(tmp_path, "--force")
    assert fresh.exit_code == 0 and json.loads((out / "population.json").read_text()) == summary


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        (["--n", "0"], "--n = 0: expected at least 1 worker per sex"),
        (["--n", "1500"], "--n = 1500: expected at most 2000 workers in all"),
        (["--correlation", "2"], "--correlation = 2.0: expected 0 to 1"),
        (["--sex", "other"], "Invalid value for '--sex'"),
        (["--set", "body.age_years=50"], "body.age_years = 50: expected not set"),
        (["--set", "body.stature_m=1.9"], "body.stature_m = 1.9: expected not set"),
    ],
)
def test_bad_population_input_is_one_line_with_exit_2(tmp_path, extra, expected) -> None:
    result, out = _population(tmp_path, *extra)
    assert result.exit_code == 2 and expected in result.output
    assert not out.exists()


def test_the_survival_curve_drops_at_once_for_a_worker_who_never_held() -> None:
    from casadi_posture.output.population_plots import survival_steps

    held = np.array([0.0, 10.0, 10.0, 20.0])
    times, counts = survival_steps(held, np.array([False, False, False, True]), 20.0)
    np.testing.assert_array_equal(times, [0.0, 10.0, 20.0])
    assert counts == [3, 1, 1]  # after 0 s, after 10 s, still holding at the end
    _, counts = survival_steps(held, np.zeros(4, dtype=bool), 20.0)
    assert counts == [3, 1, 0]  # the last one gave out at the end of its own run


def test_the_share_for_whom_a_schedule_is_sustainable(tmp_path) -> None:
    """3 workers per sex on the 2-DOF arm with 6 kg, 10 s on and 20 s off, for 5 minutes:
    population.json counts as sustainable the workers whose run went the whole 300 s with
    no group at the fatigue threshold, which summary.csv's per-group threshold times say
    by themselves; with its Wilson interval, on the console too."""
    import csv
    import json

    from casadi_posture.people.statistics import wilson

    schedule = ["--set", "schedule.t_on_s=10", "--set", "schedule.t_off_s=20"]
    result, out = _population(
        tmp_path, "--set", "simulation.duration_s=300", "--set", "loads[0].mass_kg=6", *schedule
    )
    summary = json.loads((out / "population.json").read_text())
    assert summary["schedule"] == {"t_on_s": 10.0, "t_off_s": 20.0}
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert result.exit_code == int(any(r["flags"] for r in rows)), result.output
    counts = []
    for sex, data in summary["sexes"].items():
        mine = [r for r in rows if r["body.sex"] == sex]
        never = [
            r
            for r in mine
            if r["stop"] == "completed"
            and all(v == "" for k, v in r.items() if k.startswith("fatigue_threshold_"))
        ]
        kept = data["sustainable"]
        assert (kept["n"], kept["count"]) == (3, len(never))
        assert (kept["low"], kept["high"]) == pytest.approx(wilson(len(never), 3))
        assert "sustainable, on its schedule, for the whole 300 s" in result.output
        people = {"male": "men", "female": "women"}[sex]
        assert f"{people} {len(never)} of 3," in result.output
        counts.append(len(never))
    assert 0 < sum(counts) < 6, "the load must split the workers for the test to bite"


def test_a_population_with_a_flagged_worker_exits_1_as_batch_and_whatif_do(tmp_path) -> None:
    """30 kg at arm's length is over every worker's strength at the start: every row of
    summary.csv is flagged, the console says so per sex, and the command exits 1 (it exited
    0 with 6 of 6 workers flagged); the unflagged run above exits 0."""
    import csv

    result, out = _population(tmp_path, "--set", "loads[0].mass_kg=30")
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert {r["status"] for r in rows} == {"flagged"}
    assert all("over strength" in r["flags"] for r in rows)
    assert result.exit_code == 1, result.output
    for people in ("men", "women"):
        assert f"FLAGGED: {people}: 3 of 3 worker(s) flagged" in result.output
