"""Shared fixtures: the shipped problems, small hand-built models and a headless browser."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from casadi_posture.body.tree import BodyModel, Dof, Landmark, Segment

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

#: The browser the report tests drive (Debian's package; .ci/run installs it).
CHROMIUM = Path("/usr/bin/chromium")

#: The shipped shelf scenario for a 1.65 m, 60 kg woman with the shelf raised to 1.6 m: the
#: hands cannot reach it (0.62 m ahead) and rest 0.104 m short with the arms straight.
SHORT_REACH = {
    "body.sex": "female",
    "body.stature_m": 1.65,
    "body.mass_kg": 60.0,
    "loads[0].mass_kg": 2.5,
    "loads[1].mass_kg": 2.5,
    "tasks[2].target_m[2]": 1.6,
    "tasks[3].target_m[2]": 1.6,
}


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium for the pages' tests (skipped without it, failed in CI)."""
    if not CHROMIUM.exists():
        if os.environ.get("CI"):
            pytest.fail(f"{CHROMIUM} is missing: .ci/run installs it (apt-get install chromium)")
        pytest.skip(f"no {CHROMIUM} (apt-get install chromium)")
    sync_playwright = pytest.importorskip("playwright.sync_api").sync_playwright
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=str(CHROMIUM))
        yield chromium
        chromium.close()


@pytest.fixture
def problems_dir() -> Path:
    return PROBLEMS


def chain_3d() -> BodyModel:
    """A branching 3-D tree with non-parallel, non-orthogonal axes and offsets."""
    r = np.radians
    dofs = [
        Dof(
            "a",
            None,
            (0.0, 0.0, 0.0),
            (0.0, 0.0, 1.0),
            -r(170),
            r(170),
            "a+",
            "a-",
            ("shoulder",) * 2,
        ),
        Dof(
            "b",
            "a",
            (0.02, 0.01, 0.0),
            (1.0, 0.3, 0.0),
            -r(90),
            r(90),
            "b+",
            "b-",
            ("shoulder",) * 2,
        ),
        Dof(
            "c",
            "b",
            (0.02, 0.01, -0.05),
            (0.2, 1.0, 0.4),
            -r(120),
            r(120),
            "c+",
            "c-",
            ("shoulder",) * 2,
        ),
        Dof(
            "d",
            "c",
            (0.05, -0.02, -0.30),
            (0.0, -1.0, 0.1),
            r(0),
            r(150),
            "d+",
            "d-",
            ("elbow",) * 2,
        ),
        Dof(
            "e",
            "a",
            (-0.1, 0.2, 0.05),
            (0.6, -0.2, 0.77),
            -r(60),
            r(60),
            "e+",
            "e-",
            ("trunk",) * 2,
        ),
    ]
    segments = [
        Segment("s_b", "b", 0.7, (0.03, 0.0, -0.02), "o", "p"),
        Segment("s_c", "c", 2.0, (0.04, 0.0, -0.18), "p", "q"),
        Segment("s_d", "d", 1.3, (0.10, -0.05, -0.42), "q", "tip"),
        Segment("s_e", "e", 0.9, (-0.15, 0.35, 0.10), "o", "side"),
        Segment("fixed", None, 5.0, (0.0, 0.0, 0.2), "o", "o"),
    ]
    landmarks = [
        Landmark("o", None, (0.0, 0.0, 0.0)),
        Landmark("tip", "d", (0.12, -0.05, -0.60)),
        Landmark("side", "e", (-0.2, 0.4, 0.1)),
    ]
    return BodyModel("chain_3d", dofs, segments, landmarks, gravity=9.81)
