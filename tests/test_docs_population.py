"""docs/generate/population.py: how docs/population.md counts the flags of the workers'
runs, and the lognormal mass of its ANSUR II table."""

from __future__ import annotations

import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # docs/generate is run from the repository's top folder
    sys.path.insert(0, str(ROOT))

from docs.generate.population import model, reasons  # noqa: E402


def test_flags_are_counted_per_worker_by_reason() -> None:
    """A run with two 'rests on its limit' flags counts once; a flag's own '; ' (inside its
    parentheses) does not split it; an unknown flag is 'another flag'; unflagged runs
    count nowhere."""
    rows = [
        {"flags": "over strength at the start (shoulder_flexors_r): cannot be held at all"},
        {"flags": "over strength at the start (shoulder_flexors_l): cannot be held at all"},
        {
            "flags": "39 steps where neither IK solver converged (see events.csv); end (46 s): "
            "a mirror-symmetric task held asymmetrically (hip_rotation_r 45.8°, > 5°)"
        },
        {
            "flags": "knee_flexion_r rests on its -10° limit for 63 s; elbow_flexion_r rests "
            "on its 0° limit for 63 s"
        },
        {"flags": "low-back compression 3497 N (the peak, at 72 s; above 3400 N for 2 s)"},
        {"flags": "something new"},
        {"flags": ""},
    ]
    assert reasons(rows) == (
        "2 over strength at the start, 1 with 39 steps no IK solver converged on, "
        "1 holding the mirror-symmetric task asymmetrically, "
        "1 with a joint at the end of its range for a minute or more, "
        "1 with the L5/S1 compression above the NIOSH design limit and 1 with another flag"
    )
    assert reasons([{"flags": ""}]) == "none"


def test_the_lognormal_mass_has_the_mean_and_median_of_its_log() -> None:
    """The median is exp(μ) and the mean exp(μ + σ²/2), by hand from ANSUR II's men."""
    men = model("male")
    mu, sigma = men["a"]["log_mass_mean"], men["a"]["log_mass_sd"]
    assert math.isclose(men["mass_pct"][1], math.exp(mu))
    assert math.isclose(men["mass_mean"], math.exp(mu + sigma**2 / 2))
    assert 84.0 < men["mass_pct"][1] < 85.0  # the survey's median, 84.6 kg
