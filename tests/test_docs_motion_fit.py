"""docs/generate/motion_fit.py: the rows of docs/motion.md's table of the marker fit, and
the lifts' ordinals of its shift."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # docs/generate is run from the repository's top folder
    sys.path.insert(0, str(ROOT))

from docs.generate.motion_fit import Span, fit_table, ordinal  # noqa: E402


def test_the_fit_table_gathers_each_row_s_points_by_their_landmark_or_segment() -> None:
    """A row's median and 95th percentile span its points' own (in mm); its largest is the
    largest of all of them; a cluster's markers belong to their segment's row."""
    residuals = {
        "pelvis.ASISr": np.array([0.001, 0.002, 0.003]),  # median 2 mm, largest 3 mm
        "pelvis.PSISl": np.array([0.004, 0.004, 0.010]),  # median 4 mm, largest 10 mm
        "upper_trunk.STER": np.full(3, 0.02),
        "elbow_r": np.full(3, 0.005),
        "wrist_r": np.full(3, 0.006),
        "knuckles_r": np.full(3, 0.007),
        "forearm_r.STYLr": np.full(3, 0.008),
        "hand_r.INDEX": np.full(3, 0.009),
        "shoulder_r": np.array([0.05, 0.09, 0.07]),
    }
    table = fit_table(residuals)
    assert table["pelvis"]["median_mm"] == pytest.approx((2.0, 4.0))
    assert table["pelvis"]["largest_mm"] == pytest.approx(10.0)
    assert table["joint_centres"]["median_mm"] == pytest.approx((5.0, 7.0))
    assert table["arm_markers"]["largest_mm"] == pytest.approx(9.0)
    assert table["shoulder"]["largest_cm"] == pytest.approx(9.0)
    # the 95th percentile of 50, 70, 90 mm, interpolated: 70 + 0.9 * 20
    assert table["shoulder"]["p95_mm"].high == pytest.approx(88.0)


def test_a_residual_point_in_no_row_is_refused() -> None:
    with pytest.raises(ValueError, match="'c7'"):
        fit_table({"c7": np.full(3, 0.01)})


def test_a_span_reads_as_one_number_when_its_ends_round_alike() -> None:
    assert f"{Span(1.02, 1.83):.1f}" == "1.0–1.8"
    assert f"{Span(49.32, 49.34):.1f}" == "49.3"


@pytest.mark.parametrize(
    ("n", "text"),
    [(1, "1st"), (2, "2nd"), (3, "3rd"), (4, "4th"), (11, "11th"), (12, "12th"),
     (13, "13th"), (16, "16th"), (21, "21st"), (23, "23rd"), (112, "112th")],
)  # fmt: skip
def test_ordinals(n: int, text: str) -> None:
    assert ordinal(n) == text
