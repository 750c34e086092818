"""The logic behind docs/scenarios.md's generated prose (docs/generate/scenarios_text.py):
bounds rounded up, the constraint's owners read from a timeline, the step an adjustment
settles at, and how two solvers' runs are said to agree or part."""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # docs/generate is run from the repository's top folder
    sys.path.insert(0, str(ROOT))

from docs.generate.scenarios_text import agreement, at_most, owners, stretch  # noqa: E402


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (2.7e-6, "3e-6"),
        (3.0e-6, "3e-6"),
        (3.01e-6, "4e-6"),
        (9.5e-5, "1e-4"),
        (0.0, "0"),
        (0.12, "0.2"),
    ],
)
def test_a_bound_is_rounded_up_to_one_digit(value: float, text: str) -> None:
    assert at_most(value) == text


def timeline(owner: list[str | None], load: list[float]) -> pd.DataFrame:
    """A timeline of 1 s steps with the constraint's owner and two groups' loads."""
    return pd.DataFrame(
        {
            "constraint_owner": owner,
            "load_shoulder_flexors_r_pct_mvc": load,
            "load_elbow_flexors_r_pct_mvc": [20.0] * len(load),
            "fatigue_shoulder_flexors_r": [0.8] * len(load),
            "fatigue_elbow_flexors_r": [0.5] * len(load),
        },
        index=pd.Index([float(t) for t in range(len(load))], name="time_s"),
    )


def test_owners_are_stretches_released_at_the_next_owner_or_a_free_step() -> None:
    a, b = "shoulder_flexors_r", "elbow_flexors_r"
    frame = timeline([None, a, a, None, b, a, a], [19.0] * 7)
    # a owns from 1 s and is released at 3 s; b from 4 s to 5 s; a again to the run's end
    assert list(owners(frame)) == [(a, 1.0, 3.0), (b, 4.0, 5.0), (a, 5.0, 6.0)]


def test_the_ranges_start_where_the_owners_load_stops_falling() -> None:
    group = "shoulder_flexors_r"
    # on at 1 s (that step's posture is the one before), the load falls at 2 and 3 s, then
    # wavers; released at 6 s, whose posture its constraint chose; back at 7 s
    load = [19.0, 19.0, 17.0, 15.2, 15.0, 15.1, 15.1, 19.0]
    frame = timeline([None, group, group, group, group, group, None, None], load)
    found = stretch(frame, group, 1.0, 6.0)
    assert (found["settled_s"], found["steps"], found["held_s"]) == (3.0, "over 2 steps", 5.0)
    assert found["load"] == {group: "15.0–15.2", "elbow_flexors_r": "20.0"}
    assert stretch(frame, group, 2.0, 6.0)["steps"] == "in one step"


def run(angle: list[float], events: list[tuple[float, str, str]]) -> dict:
    """A run of a one-joint body: its frame, events and summary."""
    frame = pd.DataFrame(
        {"shoulder_flexion_r_deg": angle}, index=pd.Index(range(len(angle)), name="time_s")
    )
    statistics = {"solver_statistics": {"ik_fallbacks": 0}}
    return {"frame": frame, "events": events, "summary": statistics}


def test_runs_that_part_are_said_to_part_where_they_do() -> None:
    on = [(1.0, "constraint_on", "shoulder_flexors_r")]
    a = run([10.0, 10.0, 10.0, 10.0], [*on, (3.0, "recovery_threshold", "shoulder_flexors_r")])
    b = run([10.0, 10.0, 160.0, 160.0], [*on, (2.0, "recovery_threshold", "shoulder_flexors_r")])
    same = run([10.0, 10.0, 10.0, 10.0 + 2e-6], a["events"])
    found = agreement({"0°": (a, same), "−45°": (a, b)})
    assert found["agree"] == (
        "the same events at the same seconds on the 0° line (postures within 2e-6°)"
    )
    assert "until 2 s" in found["differ"] and "from 10° to 160°" in found["differ"]
    assert "recovery threshold at 2 s (nullspace: the shoulder flexors' recovery" in found["differ"]
    assert found["fallbacks"] == "no step of either solver falls back"
