"""RULA and REBA: the transcribed tables against the papers' statements and a published
worked example, every band edge, and the mapping from our bodies' postures."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import casadi_posture as cp
from casadi_posture.data import parameters
from casadi_posture.ergonomics import reba, rula
from casadi_posture.ergonomics.posture_scores import Assumptions, score_posture
from casadi_posture.ergonomics.rula import value

ROOT = Path(__file__).resolve().parents[1]
THREE_D = ["standing_shelf_box", "standing_overhead_drill", "standing_wall_m25", "seated_assembly"]


def test_rula_grand_score_of_1_or_2_only_when_both_groups_score_2_or_less() -> None:
    """The RULA paper (stage 3): a grand score of 1 or 2 means both scores C and D are
    2 or less (posture 2 or less, no muscle use, no force) — and every such pair gives it."""
    table = value("rula.table_c")
    for c in range(1, 9):
        for d in range(1, 8):
            assert (table[c - 1][d - 1] <= 2) == (c <= 2 and d <= 2), (c, d)


@pytest.mark.parametrize(
    "name",
    [
        "rula.table_a",
        "rula.table_b",
        "rula.table_c",
        "reba.table_a",
        "reba.table_b",
        "reba.table_c",
    ],
)
def test_tables_never_fall_as_a_step_score_rises(name: str) -> None:
    """Worse postures never score lower: every table is non-decreasing along each axis
    (a transposed or mistyped entry would break it)."""
    table = np.asarray(value(name))
    for axis in range(table.ndim):
        assert (np.diff(table, axis=axis) >= 0).all(), axis


def test_every_band_table_has_one_score_more_than_edges() -> None:
    """Each band table of data/rula_reba.toml: increasing edges, a side per edge, and one
    score per interval (a missing or extra score shifts every band above it)."""
    table = parameters.load("rula_reba")
    edges = [k for k in table if k.rsplit(".", 1)[1] in ("edges", "edges_kg", "knee_edges")]
    assert len(edges) == 13
    for key in edges:
        base, kind = key.rsplit(".", 1)
        cuts = table[key].value
        assert cuts == sorted(cuts)
        prefix = "knee_" if kind == "knee_edges" else ""
        assert len(table[f"{base}.{prefix}on_edge"].value) == len(cuts)
        for name in (f"{prefix}scores", "intermittent", "static_or_repeated"):
            if f"{base}.{name}" in table:
                assert len(table[f"{base}.{name}"].value) == len(cuts) + 1, key


def test_reba_worked_example_of_rs9000_ergonomics_readme() -> None:
    """The worked example of github.com/rs9000/ergonomics (README, 'Pose Left' and 'Pose
    Right'): neck 2, trunk 2, legs 2 → A 4; upper arm 1, lower arm 2, wrist 3 (2) → B 3 (2);
    Table C 4; REBA 4 (no load, coupling or activity)."""
    left = reba.RebaInputs(
        upper_arm_deg=0.0,
        lower_arm_deg=30.0,
        wrist_deg=30.0,
        wrist_deviated_or_twisted=True,
        trunk_deg=10.0,
        neck_deg=30.0,
        bilateral_weight_bearing=False,
    )
    out = reba.score(left)
    assert (out.neck, out.trunk, out.legs, out.upper_arm, out.lower_arm, out.wrist) == (
        2, 2, 2, 1, 2, 3,
    )  # fmt: skip
    assert (out.score_a, out.score_b, out.table_c, out.reba) == (4, 3, 4, 4)
    assert out.risk == "medium" and out.action_level == 2
    right = reba.score(reba.RebaInputs(**{**left.__dict__, "wrist_deviated_or_twisted": False}))
    assert (right.wrist, right.score_b, right.table_c, right.reba) == (2, 2, 4, 4)


def test_rula_every_score_of_a_loaded_overhead_reach() -> None:
    """A hand-scored worksheet: arm raised 100° and abducted, elbow 40°, wrist extended 20°
    and deviated, twist at its end, trunk 30° forward and twisted, neck 15°, standing,
    10 kg held statically: upper arm 4+1, lower arm 2, wrist 3+1, twist 2 → A 7 (Table A
    [5][2][4][2]); +1 muscle +2 force → C 10 (row 8+); neck 2, trunk 3+1, legs 1 → B 5
    (Table B [2][4][1]); D 8 (column 7+); grand 7, action level 4."""
    out = rula.score(
        rula.RulaInputs(
            upper_arm_deg=100.0,
            arm_abducted=True,
            lower_arm_deg=40.0,
            wrist_deg=-20.0,
            wrist_deviated=True,
            wrist_twist_at_end=True,
            neck_deg=15.0,
            trunk_deg=30.0,
            trunk_twisted=True,
            static_or_repeated=True,
            load_kg=10.0,
            load_static_or_repeated=True,
        )
    )
    assert (out.upper_arm, out.lower_arm, out.wrist, out.wrist_twist, out.posture_a) == (
        5, 2, 4, 2, 7,
    )  # fmt: skip
    assert (out.muscle_use, out.force, out.score_c) == (1, 2, 10)
    assert (out.neck, out.trunk, out.legs, out.posture_b, out.score_d) == (2, 4, 1, 5, 8)
    assert (out.grand, out.action_level) == (7, 4)
    assert out.action == "investigation and changes are required immediately"


@pytest.mark.parametrize(
    ("angle", "expected"),
    [(-300.0, 2), (-20.01, 2), (-20.0, 1), (20.0, 1), (20.01, 2), (45.0, 2), (45.01, 3),
     (89.99, 3), (90.0, 4), (400.0, 4)],
)  # fmt: skip
def test_rula_upper_arm_bands(angle: float, expected: int) -> None:
    assert rula.upper_arm(rula.RulaInputs(upper_arm_deg=angle, lower_arm_deg=80.0)) == expected


@pytest.mark.parametrize(
    ("angle", "expected"), [(-5.0, 2), (0.0, 2), (60.0, 1), (100.0, 1), (100.01, 2), (999.0, 2)]
)
def test_lower_arm_bands(angle: float, expected: int) -> None:
    x = rula.RulaInputs(upper_arm_deg=0.0, lower_arm_deg=angle)
    assert rula.lower_arm(x) == expected
    assert reba.lower_arm(reba.RebaInputs(upper_arm_deg=0.0, lower_arm_deg=angle)) == expected


def test_rula_wrist_neck_trunk_edges() -> None:
    tol = value("neutral_tolerance")

    def r(**kw: float) -> rula.RulaInputs:
        return rula.RulaInputs(upper_arm_deg=0.0, lower_arm_deg=80.0, **kw)  # type: ignore[arg-type]

    assert [rula.wrist(r(wrist_deg=a)) for a in (tol, tol + 0.01, 14.99, 15.0, -15.0)] == [
        1, 2, 2, 3, 3,
    ]  # fmt: skip
    assert [rula.neck(r(neck_deg=a)) for a in (-tol, -tol - 0.01, 10.0, 10.01, 20.0)] == [
        1, 4, 1, 2, 3,
    ]  # fmt: skip
    assert [rula.trunk(r(trunk_deg=a)) for a in (tol, 20.0, 20.01, 59.99, 60.0, -40.0)] == [
        1, 2, 3, 3, 4, 3,
    ]  # fmt: skip
    assert rula.trunk(r(trunk_deg=70.0, trunk_twisted=True, trunk_side_bent=True)) == 6
    assert rula.upper_arm(r(arm_supported=True)) == 1  # never below the table's first row


def test_rula_force_bands() -> None:
    def force(kg: float, static: bool = False, shock: bool = False) -> int:
        return rula.force(
            rula.RulaInputs(0.0, 80.0, load_kg=kg, load_static_or_repeated=static, shock=shock)
        )

    assert [force(kg) for kg in (0.0, 1.99, 2.0, 10.0, 10.01)] == [0, 0, 1, 1, 2]
    assert [force(kg, True) for kg in (1.99, 2.0, 10.0, 10.01)] == [0, 2, 2, 3]
    assert force(0.5, shock=True) == 3


def test_reba_edges() -> None:
    def x(**kw: float) -> reba.RebaInputs:
        return reba.RebaInputs(**{"upper_arm_deg": 0.0, "lower_arm_deg": 80.0, **kw})  # type: ignore[arg-type]

    assert [reba.upper_arm(x(upper_arm_deg=a)) for a in (-21.0, 45.0, 90.0, 90.01)] == [2, 2, 3, 4]
    assert [reba.trunk(x(trunk_deg=a)) for a in (0.0, 20.0, 20.01, 60.0, 60.01, -20.0, -20.01)] == [
        1, 2, 3, 3, 4, 2, 3,
    ]  # fmt: skip
    assert [reba.neck(x(neck_deg=a)) for a in (20.0, 20.01, -10.0)] == [1, 2, 2]
    assert [reba.wrist(x(wrist_deg=a)) for a in (15.0, -15.01)] == [1, 2]
    assert [reba.legs(x(knee_deg=a)) for a in (29.99, 30.0, 60.0, 60.01)] == [1, 2, 2, 3]
    assert reba.legs(x(knee_deg=90.0, seated=True)) == 1
    assert [reba.load(x(load_kg=kg)) for kg in (4.99, 5.0, 10.0, 10.01)] == [0, 1, 1, 2]
    assert reba.load(x(load_kg=12.0, shock=True)) == 3
    assert reba.activity(x(static=True, repeated=True, rapid_changes=True)) == 3
    assert [reba.action_level(s)[0] for s in (1, 2, 3, 4, 7, 8, 10, 11, 15)] == [
        0, 1, 1, 2, 2, 3, 3, 4, 4,
    ]  # fmt: skip
    assert reba.action_level(11)[1:] == ("very high", "necessary now")


def test_worst_case_stays_in_the_tables() -> None:
    """Every adjustment at once reads the last rows: RULA 7, REBA 12 + 3 = 15."""
    worst = rula.score(
        rula.RulaInputs(
            200.0, 0.0, 90.0, True, True, False, True, True, True, -40.0, True, True, 90.0,
            False, True, True, False, True, 50.0, True, True,
        )
    )  # fmt: skip
    assert (worst.posture_a, worst.posture_b, worst.grand) == (9, 9, 7)
    most = reba.score(
        reba.RebaInputs(
            120.0, 0.0, 40.0, 90.0, True, 40.0, True, False, 90.0, False, 30.0, True, True,
            True, False, True, "unacceptable", True, True, True,
        )
    )  # fmt: skip
    assert (most.table_c, most.reba, most.action_level) == (12, 15, 4)


def test_bad_inputs_are_refused() -> None:
    with pytest.raises(ValueError, match="finite"):
        rula.RulaInputs(upper_arm_deg=math.nan, lower_arm_deg=80.0)
    with pytest.raises(ValueError, match="load"):
        reba.RebaInputs(upper_arm_deg=0.0, lower_arm_deg=80.0, load_kg=-1.0)
    with pytest.raises(ValueError, match="coupling"):
        reba.RebaInputs(0.0, 80.0, coupling="bad")  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def standing() -> cp.Problem:
    return cp.load(ROOT / "problems" / "standing_shelf_box.toml")


def _at(problem: cp.Problem, **angles_deg: float) -> np.ndarray:
    q = np.zeros(problem.body.n)
    for name, deg in angles_deg.items():
        q[problem.body.index[name]] = math.radians(deg)
    return q


def test_upright_zero_posture_scores_the_lowest_bands(standing: cp.Problem) -> None:
    right, left = score_posture(standing.body, _at(standing), assumptions=Assumptions(static=False))
    for side in (right, left):
        x = side.rula_inputs
        assert abs(x.upper_arm_deg) < 1e-9 and abs(x.trunk_deg) < 1e-9
        r, b = side.rula, side.reba
        assert (r.upper_arm, r.wrist, r.wrist_twist, r.neck, r.trunk, r.legs) == (1, 1, 1, 1, 1, 1)
        assert r.lower_arm == 2  # the straight elbow lies below 60°
        assert (b.trunk, b.neck, b.legs, b.upper_arm, b.wrist, b.reba) == (1, 1, 1, 1, 1, 1)


def test_arm_angles_follow_our_conventions(standing: cp.Problem) -> None:
    def right(**angles: float) -> rula.RulaInputs:
        return score_posture(standing.body, _at(standing, **angles))[0].rula_inputs

    flexed = right(shoulder_flexion_r=100.0)
    assert flexed.upper_arm_deg == pytest.approx(100.0)
    assert rula.upper_arm(flexed) == 4
    assert right(shoulder_flexion_r=-30.0).upper_arm_deg == pytest.approx(-30.0)
    sideways = right(shoulder_abduction_r=90.0)
    assert sideways.upper_arm_deg == pytest.approx(90.0) and sideways.arm_abducted
    bent = right(elbow_flexion_r=80.0, wrist_flexion_r=-20.0, wrist_deviation_r=10.0)
    assert bent.lower_arm_deg == pytest.approx(80.0) and bent.wrist_deg == pytest.approx(-20.0)
    assert bent.wrist_deviated and not bent.wrist_twist_at_end
    assert right(forearm_pronation_r=80.0).wrist_twist_at_end
    across = right(shoulder_flexion_r=60.0, shoulder_rotation_r=60.0, elbow_flexion_r=90.0)
    assert across.arm_across_or_out  # the forearm swung in across the body


def test_trunk_angles_follow_our_conventions(standing: cp.Problem) -> None:
    def trunk(**angles: float) -> rula.RulaInputs:
        return score_posture(standing.body, _at(standing, **angles))[0].rula_inputs

    assert trunk(lumbar_flexion=30.0).trunk_deg == pytest.approx(30.0)
    assert trunk(lumbar_flexion=-15.0).trunk_deg == pytest.approx(-15.0)
    # the legs tilt the pelvis: the trunk's inclination from the vertical adds them up
    assert trunk(lumbar_flexion=20.0, hip_flexion_r=15.0, hip_flexion_l=15.0).trunk_deg == (
        pytest.approx(35.0, abs=1e-6)
    )
    bent = trunk(lumbar_bending=25.0)
    assert bent.trunk_side_bent and not bent.trunk_twisted and abs(bent.trunk_deg) < 1e-9
    assert trunk(lumbar_rotation=-25.0).trunk_twisted
    knees = score_posture(standing.body, _at(standing, knee_flexion_l=45.0))[0]
    assert knees.reba_inputs.knee_deg == pytest.approx(45.0) and knees.reba.legs == 2


def test_loads_per_side_for_rula_and_in_total_for_reba(standing: cp.Problem) -> None:
    right, left = score_posture(standing.body, standing.posture, standing.loads)
    assert right.rula_inputs.load_kg == pytest.approx(3.0)
    assert left.rula_inputs.load_kg == pytest.approx(3.0)
    assert right.reba_inputs.load_kg == pytest.approx(6.0) and right.reba.load == 1


@pytest.mark.parametrize("name", THREE_D)
def test_shipped_start_postures_score_within_the_tables(name: str) -> None:
    problem = cp.load(ROOT / "problems" / f"{name}.toml")
    sides = score_posture(problem.body, problem.posture, problem.loads)
    assert [s.side for s in sides] == ["r", "l"]
    for side in sides:
        r, b = side.rula, side.reba
        assert 1 <= r.posture_a <= 9 and 1 <= r.posture_b <= 9 and 1 <= r.grand <= 7
        assert 1 <= r.action_level <= 4 and r.action
        assert 1 <= b.posture_a <= 9 and 1 <= b.posture_b <= 9 and 1 <= b.table_c <= 12
        assert 1 <= b.reba <= 15 and 0 <= b.action_level <= 4 and b.risk and b.action
        for number in [*side.rula_inputs.__dict__.values(), *side.reba_inputs.__dict__.values()]:
            assert not isinstance(number, float) or math.isfinite(number)
        assert "neck" in side.assumed and "coupling" in side.assumed
    if name == "seated_assembly":
        assert "legs (seated)" in sides[0].assumed


def test_planar_arms_score_their_joints_and_say_the_rest_is_assumed() -> None:
    arm = cp.load(ROOT / "problems" / "holding_horizontal.toml")
    (side,) = score_posture(arm.body, arm.posture, arm.loads)
    assert side.side == "arm"
    assert side.rula_inputs.upper_arm_deg == pytest.approx(math.degrees(arm.posture[0]))
    assert side.rula_inputs.load_kg == pytest.approx(2.5) and side.rula.force == 2
    assert {"trunk upright", "wrist neutral", "neck"} <= set(side.assumed)
    elbow = cp.load(ROOT / "problems" / "frontal_elbow.toml")
    (side,) = score_posture(elbow.body, elbow.posture)
    assert side.rula_inputs.upper_arm_deg == 90.0 and side.rula.upper_arm == 5
    assert any("90° abduction" in a for a in side.assumed)
