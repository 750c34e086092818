"""Fatigue models: accumulation (paper eq. 7), the recovery laws and the 3CC-r."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from casadi_posture.biomech.endurance import endurance_model
from casadi_posture.biomech.fatigue import (
    RECOVERY_LAWS,
    HoldingTimeFatigue,
    ThreeCompartmentFatigue,
    fatigue_model,
)
from casadi_posture.errors import ProblemError

R_SHOULDER = 0.00168
R_ELBOW = 0.00094


def holding(regions: list[str], endurance: str = "manenica", **kwargs: float) -> HoldingTimeFatigue:
    model = fatigue_model(
        "threshold", regions=regions, endurance=endurance_model(endurance), **kwargs
    )
    assert isinstance(model, HoldingTimeFatigue)
    return model


def hold(model, state: np.ndarray, load: list[float], steps: list[float]) -> np.ndarray:
    for dt in steps:
        state = model.step(state, np.array(load), dt)
    return state


@pytest.mark.parametrize("endurance", ["manenica", "frey_law_avin", "rohmert"])
def test_constant_load_accumulates_held_time_over_endurance(endurance: str) -> None:
    model = holding(["shoulder", "elbow"], endurance)
    loads = [40.0, 25.0]
    steps = [0.05] * 1000
    fatigue = hold(model, model.initial_state(), loads, steps)
    expected = [
        50.0 / float(model.endurance.endurance_time_s(load, region))
        for load, region in zip(loads, ["shoulder", "elbow"], strict=True)
    ]
    np.testing.assert_allclose(fatigue, expected, rtol=1e-12)


def test_uneven_steps_give_the_same_fatigue() -> None:
    model = holding(["shoulder"])
    rng = np.random.default_rng(7)
    steps = rng.uniform(0.001, 0.3, size=800)
    fatigue = hold(model, model.initial_state(), [56.0], list(steps))
    manenica_s = 60 * math.exp(2.70 - 0.0448 * 56.0)
    np.testing.assert_allclose(fatigue, [steps.sum() / manenica_s], rtol=1e-12)


def test_level_is_fatigue_itself() -> None:
    model = holding(["shoulder", "elbow"])
    state = np.array([0.3, 0.9])
    np.testing.assert_array_equal(model.level(state, np.array([0.0, 50.0])), state)


def test_unloaded_half_joint_recovers_with_rest_multiplier() -> None:
    model = holding(["shoulder", "elbow"])
    start = np.array([0.8, 0.8])
    fatigue = hold(model, start, [0.0, 0.0], [0.5] * 40)
    np.testing.assert_allclose(
        fatigue, 0.8 * np.exp(-15 * np.array([R_SHOULDER, R_ELBOW]) * 20.0), rtol=1e-12
    )


def test_loaded_below_threshold_recovers_without_multiplier() -> None:
    model = holding(["shoulder", "elbow"])
    fatigue = hold(model, np.array([0.8, 0.6]), [15.0, 0.5], [2.0] * 50)
    np.testing.assert_allclose(
        fatigue, [0.8, 0.6] * np.exp(-np.array([R_SHOULDER, R_ELBOW]) * 100.0), rtol=1e-12
    )


def test_shoulder_falls_from_fatigue_to_recovery_threshold_in_18_65_s() -> None:
    model = holding(["shoulder"])
    assert math.log(1.6) / (15 * R_SHOULDER) == pytest.approx(18.65, abs=0.005)
    at_18_6 = model.step(np.array([0.8]), np.array([0.0]), 18.6)
    at_18_7 = model.step(np.array([0.8]), np.array([0.0]), 18.7)
    assert at_18_6[0] > 0.5 > at_18_7[0]


def test_user_threshold_moves_the_switch() -> None:
    default = holding(["shoulder"])
    lowered = holding(["shoulder"], recovery_threshold_pct_mvc=5.0)
    assert default.step(np.array([0.5]), np.array([10.0]), 1.0)[0] < 0.5
    assert lowered.step(np.array([0.5]), np.array([10.0]), 1.0)[0] > 0.5
    threshold = next(p for p in lowered.parameters() if p.name.endswith("load_threshold"))
    assert (threshold.value, threshold.status) == (5.0, "user")


def test_holding_time_parameters_name_what_is_used() -> None:
    model = holding(["shoulder", "elbow", "shoulder"], "frey_law_avin")
    names = [p.name for p in model.parameters()]
    assert names == [
        "endurance.frey_law_avin.shoulder.b0",
        "endurance.frey_law_avin.shoulder.b1",
        "endurance.frey_law_avin.elbow.b0",
        "endurance.frey_law_avin.elbow.b1",
        "fatigue.load_threshold",
        "fatigue.rest_multiplier",
        "fatigue.frey_law_2012.shoulder.recovery_rate",
        "fatigue.frey_law_2012.elbow.recovery_rate",
    ]


def test_a_region_without_data_takes_the_general_rates_and_says_so() -> None:
    model = ThreeCompartmentFatigue(["shoulder", "wrist"])
    general = {p.name: p for p in ThreeCompartmentFatigue(["general"]).parameters()}
    records = {p.name: p for p in model.parameters()}
    wrist = records["fatigue.frey_law_2012.wrist.recovery_rate"]
    assert "no fit for a region named 'wrist'" in wrist.source
    assert wrist.value == general["fatigue.frey_law_2012.general.recovery_rate"].value
    assert "no fit" not in records["fatigue.frey_law_2012.shoulder.recovery_rate"].source


def test_negative_time_step_is_a_problem_error() -> None:
    model = holding(["elbow"])
    with pytest.raises(ProblemError, match="dt_s"):
        model.step(model.initial_state(), np.array([30.0]), -0.1)


def test_unknown_fatigue_model_names_value_and_allowed_names() -> None:
    with pytest.raises(ProblemError, match=r"fatigue\.recovery_law = 'nope'") as error:
        fatigue_model("nope", regions=["elbow"], endurance=endurance_model("manenica"))
    assert "one of threshold, continuous, 3cc_r" in str(error.value)


def test_3cc_r_refuses_a_recovery_threshold() -> None:
    with pytest.raises(ProblemError, match="load_threshold_pct_mvc"):
        fatigue_model(
            "3cc_r",
            regions=["elbow"],
            endurance=endurance_model("manenica"),
            recovery_threshold_pct_mvc=10.0,
        )


def test_registry_builds_each_model_by_name() -> None:
    manenica = endurance_model("manenica")
    for name in RECOVERY_LAWS:
        assert fatigue_model(name, regions=["elbow"], endurance=manenica).name == name


@pytest.fixture(scope="module")
def three_cc() -> ThreeCompartmentFatigue:
    return ThreeCompartmentFatigue(["shoulder", "elbow", "hand", "knee"])


@pytest.fixture(scope="module")
def shoulder_endurance(three_cc: ThreeCompartmentFatigue) -> dict[float, float]:
    loads = np.array([20.0, 30.0, 50.0, 70.0])
    times = three_cc.endurance_time_s(loads, "shoulder")
    return dict(zip(loads.tolist(), times.tolist(), strict=True))


loads = st.one_of(st.just(0.0), st.floats(0.0, 120.0))
profiles = st.lists(
    st.tuples(st.lists(loads, min_size=4, max_size=4), st.floats(0.0, 2.0)),
    min_size=1,
    max_size=15,
)


@settings(max_examples=30, deadline=None)
@given(profile=profiles)
def test_3cc_r_conserves_the_motor_unit_pool(three_cc, profile) -> None:
    state = three_cc.initial_state()
    for step_loads, dt in profile:
        state = three_cc.step(state, np.array(step_loads), dt)
        np.testing.assert_allclose(state.sum(axis=1), 100.0, rtol=0, atol=1e-9)
        assert (state >= 0).all()


def test_3cc_r_conserves_the_pool_on_a_seeded_profile_with_rests(three_cc) -> None:
    rng = np.random.default_rng(2008)
    state = three_cc.initial_state()
    for _ in range(150):
        loads = rng.uniform(0.0, 80.0, size=4) * (rng.uniform(size=4) > 0.3)
        state = three_cc.step(state, loads, float(rng.uniform(0.0, 3.0)))
        np.testing.assert_allclose(state.sum(axis=1), 100.0, rtol=0, atol=1e-9)
    assert state[:, 2].max() > 1.0


@pytest.mark.parametrize(("load", "simulated"), [(20.0, 275), (30.0, 145), (50.0, 58), (70.0, 24)])
def test_3cc_shoulder_endurance_matches_biomech_data_simulation(
    shoulder_endurance, load: float, simulated: float
) -> None:
    assert shoulder_endurance[load] == pytest.approx(simulated, rel=0.15)


@pytest.mark.parametrize(("load", "power_model"), [(20.0, 283), (30.0, 135), (50.0, 53)])
def test_3cc_shoulder_endurance_matches_frey_law_avin(
    shoulder_endurance, load: float, power_model: float
) -> None:
    assert shoulder_endurance[load] == pytest.approx(power_model, rel=0.15)


def test_3cc_endurance_is_infinite_below_sustainable_level(three_cc) -> None:
    sustainable = 100 * R_SHOULDER / (R_SHOULDER + 0.01820)
    times = three_cc.endurance_time_s([0.0, sustainable - 0.01], "shoulder")
    assert np.isinf(times).all()


def test_3cc_endurance_beyond_the_horizon_is_the_sustained_phase_closed_form(three_cc) -> None:
    """A load just above the sustainable level fails after hours: past the Euler horizon the
    closed form takes over, and agrees within 1 % with Euler run all the way (it leaves out
    the seconds-long transients of MA at the start and near failure)."""
    sustainable = 100 * R_SHOULDER / (R_SHOULDER + 0.01820)
    load = sustainable + 1.0
    euler = float(three_cc.endurance_time_s(load, "shoulder", dt_s=0.05, horizon_s=1e6))
    closed = float(three_cc.endurance_time_s(load, "shoulder", dt_s=0.05, horizon_s=10.0))
    assert 600 < euler < np.inf
    assert closed == pytest.approx(euler, rel=1e-2)


def test_3cc_level_reaches_one_at_the_endurance_time(three_cc) -> None:
    shoulder = ThreeCompartmentFatigue(["shoulder"])
    endurance_s = float(three_cc.endurance_time_s(50.0, "shoulder"))
    steps = round(endurance_s / shoulder.max_substep_s)
    state = shoulder.initial_state()
    load = np.array([50.0])
    levels = []
    for _ in range(steps):
        state = shoulder.step(state, load, shoulder.max_substep_s)
        levels.append(float(shoulder.level(state, load)[0]))
    assert levels[-2] < 1.0
    assert levels[-1] == 1.0


def test_3cc_level_is_fatigued_share_of_spare_capacity(three_cc) -> None:
    state = np.array([[30.0, 40.0, 30.0], [0.0, 50.0, 50.0], [0.0, 100.0, 0.0], [0, 90, 10]])
    levels = three_cc.level(state, np.array([40.0, 0.0, 100.0, 120.0]))
    np.testing.assert_allclose(levels, [0.5, 0.5, 1.0, 1.0])


def test_3cc_substeps_split_a_long_step(three_cc) -> None:
    coarse = ThreeCompartmentFatigue(["shoulder"], max_substep_s=0.05)
    state = coarse.initial_state()
    one_step = coarse.step(state, np.array([40.0]), 1.0)
    twenty = hold(coarse, state, [40.0], [0.05] * 20)
    np.testing.assert_allclose(one_step, twenty, rtol=1e-12)
    assert not np.allclose(one_step, three_cc.step(three_cc.initial_state(), 40.0, 1.0)[:1])


def test_3cc_rest_multiplier_speeds_recovery_at_zero_load() -> None:
    shoulder = ThreeCompartmentFatigue(["shoulder", "shoulder"])
    tired = hold(shoulder, shoulder.initial_state(), [50.0, 50.0], [1.0] * 40)
    settled = shoulder.step(tired, np.array([0.0, 2.0]), 5.0)
    later = shoulder.step(settled, np.array([0.0, 2.0]), 60.0)
    assert later[0, 2] < later[1, 2]
    assert later[0, 2] / settled[0, 2] == pytest.approx(math.exp(-15 * R_SHOULDER * 60.0), rel=1e-3)


def test_3cc_parameters_name_what_is_used() -> None:
    model = fatigue_model(
        "3cc_r", regions=["elbow", "elbow"], endurance=endurance_model("manenica")
    )
    names = {p.name: p.value for p in model.parameters()}
    assert names == {
        "fatigue.three_compartment.development_gain": 10.0,
        "fatigue.three_compartment.relaxation_gain": 10.0,
        "fatigue.rest_multiplier": 15.0,
        "fatigue.frey_law_2012.elbow.fatigue_rate": 0.00912,
        "fatigue.frey_law_2012.elbow.recovery_rate": R_ELBOW,
        "fatigue.numerics.max_substep": 0.01,
    }


# The recovery laws side by side: recovery from 0.8 to 0.5 (the hysteresis thresholds).


def _time_to(model, state: np.ndarray, load: float, level: float, dt: float = 0.05) -> float:
    """Time [s] until the fatigue level falls to ``level`` under a constant load."""
    t = 0.0
    while model.level(state, np.array([load]))[0] > level:
        state = model.step(state, np.array([load]), dt)
        t += dt
        assert t < 5000
    return t


@pytest.mark.parametrize("law", ["threshold", "continuous"])
@pytest.mark.parametrize(("load", "multiplier"), [(0.0, 15.0), (10.0, 1.0)])
def test_recovery_from_0_8_to_0_5_has_the_closed_form(law: str, load: float, multiplier: float):
    """At or below T_0 both laws decay as dF/dt = -r·R·F: ln(0.8/0.5)/(r·R), with r = 15
    unloaded (18.65 s at the shoulder) and 1 at 10 %MVC (280 s)."""
    model = fatigue_model(law, regions=["shoulder"], endurance=endurance_model("manenica"))
    took = _time_to(model, np.array([0.8]), load, 0.5)
    assert took == pytest.approx(math.log(1.6) / (multiplier * R_SHOULDER), abs=0.05)


def test_the_continuous_law_recovers_under_load_and_settles() -> None:
    """dF/dt = 1/ET - R·F above T_0: F(t) = F∞ + (F0 - F∞)·exp(-R·t) with F∞ = 1/(ET·R),
    whatever the steps. At 20 %MVC the elbow's F∞ = 2.9 > 1, so it still tires, but reaches
    F = 1 after -ln(1 - 1/F∞)/R = 452 s instead of the threshold law's ET = 368 s."""
    model = fatigue_model("continuous", regions=["elbow"], endurance=endurance_model("manenica"))
    et = 60 * math.exp(2.70 - 0.0448 * 20.0)
    settled = 1.0 / (et * R_ELBOW)
    state = np.array([0.3])
    for dt in [0.7, 3.0, 11.0, 0.1, 40.0]:
        state = model.step(state, np.array([20.0]), dt)
    t = 0.7 + 3.0 + 11.0 + 0.1 + 40.0
    assert state[0] == pytest.approx(settled + (0.3 - settled) * math.exp(-R_ELBOW * t), rel=1e-12)
    exhausted = float(model.endurance_time_s(20.0, "elbow"))
    assert exhausted == pytest.approx(-math.log(1 - 1 / settled) / R_ELBOW, rel=1e-12)
    assert exhausted > et  # slower than the threshold law, which takes exactly ET


def test_the_3cc_r_law_recovers_unloaded_but_not_at_10_pct_mvc() -> None:
    """3CC-r: unloaded, MF decays at r·R (15 × 0.00168 /s at the shoulder): 0.8 -> 0.5 in about
    ln(1.6)/(15·R) = 18.65 s. At 10 %MVC, above the shoulder's sustainable 8.5 %MVC, the level
    keeps rising: no recovery at all."""
    model = fatigue_model("3cc_r", regions=["shoulder"], endurance=endurance_model("manenica"))
    rested = np.array([[0.0, 20.0, 80.0]])
    assert _time_to(model, rested, 0.0, 0.5, dt=0.01) == pytest.approx(
        math.log(1.6) / (15 * R_SHOULDER), rel=0.01
    )
    state = np.array([[10.0, 10.0, 80.0]])
    before = model.level(state, np.array([10.0]))[0]
    for _ in range(600):
        state = model.step(state, np.array([10.0]), 1.0)
    assert model.level(state, np.array([10.0]))[0] > before
