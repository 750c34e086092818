"""de Leva (1996) Table 4 segment inertia against de Leva's published values."""

from __future__ import annotations

import pytest

from casadi_posture.body.anthropometry import SEGMENTS, reference_body, segment_inertia
from casadi_posture.errors import ProblemError


def reference_segment(name: str, sex: str = "male"):
    stature, body_mass = reference_body(sex)
    return segment_inertia(name, sex=sex, stature=stature, body_mass=body_mass)


def test_reference_bodies() -> None:
    assert reference_body("male") == (1.741, 73.0)
    assert reference_body("female") == (1.735, 61.9)


def test_segment_names_cover_table_4() -> None:
    assert set(SEGMENTS) == {
        "head_neck",
        "head",
        "trunk",
        "trunk_from_suprasternale",
        "upper_trunk",
        "middle_trunk",
        "lower_trunk",
        "upper_arm",
        "forearm",
        "hand",
        "hand_to_fingertip",
        "thigh",
        "shank",
        "shank_to_ankle",
        "foot",
    }


@pytest.mark.parametrize(
    ("name", "length", "mass", "com", "inertia"),
    [
        ("upper_arm", 0.2817, 1.978, 0.1626, 0.01136),
        ("forearm", 0.2689, 1.183, 0.1230, 0.00600),
        ("hand", 0.0862, 0.445, 0.0681, 0.00087),
    ],
)
def test_reference_male_arm_matches_default_set(
    name: str, length: float, mass: float, com: float, inertia: float
) -> None:
    segment = reference_segment(name)
    assert segment.length == pytest.approx(length, abs=5e-5)
    assert segment.mass == pytest.approx(mass, abs=5e-4)
    assert segment.com_distance == pytest.approx(com, abs=5e-5)
    r_transverse = segment.radii_of_gyration[1]
    assert segment.mass * r_transverse**2 == pytest.approx(inertia, abs=5e-6)


@pytest.mark.parametrize(
    ("name", "mass"), [("upper_arm", 1.578), ("forearm", 0.854), ("hand", 0.347)]
)
def test_reference_female_arm_masses(name: str, mass: float) -> None:
    assert reference_segment(name, "female").mass == pytest.approx(mass, abs=5e-4)


@pytest.mark.parametrize("sex", ["male", "female"])
def test_body_partition_mass_fractions_sum_to_one(sex: str) -> None:
    stature, _ = reference_body(sex)

    def fraction(name: str) -> float:
        return segment_inertia(name, sex=sex, stature=stature, body_mass=1.0).mass

    limbs = sum(fraction(n) for n in ("upper_arm", "forearm", "hand", "thigh", "shank", "foot"))
    total = fraction("head_neck") + fraction("trunk") + 2 * limbs
    assert total == pytest.approx(1.0, abs=2e-3)


LENGTH_OVER_STATURE = {
    "male": {
        "head_neck": 0.1395,
        "head": 0.1168,
        "trunk": 0.3465,
        "trunk_from_suprasternale": 0.3055,
        "upper_trunk": 0.1391,
        "middle_trunk": 0.1238,
        "lower_trunk": 0.0837,
        "upper_arm": 0.1618,
        "forearm": 0.1545,
        "hand": 0.0495,
        "hand_to_fingertip": 0.1079,
        "thigh": 0.2425,
        "shank": 0.2493,
        "shank_to_ankle": 0.2529,
        "foot": 0.1482,
    },
    "female": {
        "head_neck": 0.1405,
        "head": 0.1154,
        "trunk": 0.3543,
        "trunk_from_suprasternale": 0.3051,
        "upper_trunk": 0.1314,
        "middle_trunk": 0.1183,
        "lower_trunk": 0.1046,
        "upper_arm": 0.1586,
        "forearm": 0.1523,
        "hand": 0.0450,
        "hand_to_fingertip": 0.0980,
        "thigh": 0.2124,
        "shank": 0.2492,
        "shank_to_ankle": 0.2528,
        "foot": 0.1316,
    },
}


@pytest.mark.parametrize("sex", ["male", "female"])
def test_length_over_stature_column(sex: str) -> None:
    stature, _ = reference_body(sex)
    ratios = {name: reference_segment(name, sex).length / stature for name in SEGMENTS}
    assert ratios == pytest.approx(LENGTH_OVER_STATURE[sex], abs=5e-4)


def test_scaling_by_mass_and_stature() -> None:
    base = reference_segment("forearm")
    stature, body_mass = reference_body("male")
    heavier = segment_inertia("forearm", sex="male", stature=stature, body_mass=2 * body_mass)
    taller = segment_inertia("forearm", sex="male", stature=1.1 * stature, body_mass=body_mass)
    assert heavier.mass == pytest.approx(2 * base.mass)
    assert heavier.length == pytest.approx(base.length)
    assert taller.length == pytest.approx(1.1 * base.length)
    assert taller.com_distance == pytest.approx(1.1 * base.com_distance)
    assert taller.radii_of_gyration == pytest.approx([1.1 * r for r in base.radii_of_gyration])
    assert taller.mass == pytest.approx(base.mass)


@pytest.mark.parametrize(
    ("name", "proximal", "distal"),
    [
        ("upper_arm", "shoulder joint centre", "elbow joint centre"),
        ("hand", "wrist joint centre", "third metacarpale"),
        ("shank", "knee joint centre", "lateral malleolus"),
        ("shank_to_ankle", "knee joint centre", "ankle joint centre"),
        ("trunk_from_suprasternale", "suprasternale", "mid-hip joint centre"),
    ],
)
def test_end_points(name: str, proximal: str, distal: str) -> None:
    for sex in ("male", "female"):
        segment = reference_segment(name, sex)
        assert (segment.proximal, segment.distal) == (proximal, distal)


def test_provenance_records_the_scaled_values() -> None:
    segment = segment_inertia("upper_arm", sex="male", stature=1.80, body_mass=80.0)
    records = {p.name: p for p in segment.parameters}
    assert set(records) == {
        "segment.upper_arm.length",
        "segment.upper_arm.mass",
        "segment.upper_arm.com_distance",
        "segment.upper_arm.radius_of_gyration.sagittal",
        "segment.upper_arm.radius_of_gyration.transverse",
        "segment.upper_arm.radius_of_gyration.longitudinal",
    }
    mass = records["segment.upper_arm.mass"]
    assert (mass.value, mass.unit) == (segment.mass, "kg")
    assert "Table 4 (male)" in mass.source
    assert "0.0271" in mass.source and "80 kg" in mass.source
    assert records["segment.upper_arm.com_distance"].value == segment.com_distance
    for record in records.values():
        assert (record.status, record.evidence) == ("verified", "C2")


def test_every_segment_loads_for_both_sexes() -> None:
    for sex in ("male", "female"):
        for name in SEGMENTS:
            segment = reference_segment(name, sex)
            assert segment.mass > 0 and 0 < segment.com_fraction < 1
            assert all(0 < r < segment.length for r in segment.radii_of_gyration)


@pytest.mark.parametrize(
    ("name", "sex", "stature", "body_mass", "shown"),
    [
        ("tail", "male", 1.7, 70.0, "'tail'"),
        ("hand", "robot", 1.7, 70.0, "'robot'"),
        ("hand", "male", 1.7, -3.0, "-3.0"),
        ("hand", "male", 0.0, 70.0, "0.0"),
    ],
)
def test_bad_input_raises_problem_error(
    name: str, sex: str, stature: float, body_mass: float, shown: str
) -> None:
    with pytest.raises(ProblemError) as caught:
        segment_inertia(name, sex=sex, stature=stature, body_mass=body_mass)  # type: ignore[arg-type]
    assert shown in str(caught.value)


def test_unknown_choices_are_listed() -> None:
    with pytest.raises(ProblemError, match="'upper_arm'"):
        segment_inertia("tail", sex="male", stature=1.7, body_mass=70.0)
    with pytest.raises(ProblemError, match="'male', 'female'"):
        reference_body("robot")  # type: ignore[arg-type]
