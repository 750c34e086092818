"""Gravity torques printed by ``torques`` reproduced by pinocchio from ``describe --json``.

Pinocchio is an independent rigid-body library: it rebuilds the tree from the printed
joint origins, axes, segment masses and centres of mass, and its generalized gravity
g(q) must equal -τe to 1e-9 N·m.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import PROBLEMS
from pinocchio_bodies import pinocchio_model

from casadi_posture.cli import main

pin = pytest.importorskip("pinocchio")


BENCHMARKS = PROBLEMS.parent / "benchmarks" / "problems"


@pytest.mark.parametrize(
    "path",
    [
        PROBLEMS / "holding_m45.toml",
        PROBLEMS / "frontal_elbow.toml",
        BENCHMARKS / "humanoid_42.toml",
    ],
    ids=lambda p: p.stem,
)
def test_torques_match_pinocchio_gravity(path: Path) -> None:
    runner = CliRunner()
    path = str(path)
    described = runner.invoke(main, ["describe", path, "--json"])
    assert described.exit_code == 0, described.output
    pm, dofs = pinocchio_model(json.loads(described.stdout))
    data = pm.createData()
    rng = np.random.default_rng(11)
    ranges = np.radians([d["range_deg"] for d in json.loads(described.stdout)["dofs"]])
    for q in rng.uniform(ranges[:, 0], ranges[:, 1], size=(8, len(dofs))):
        args = [
            item
            for name_, angle in zip(dofs, np.degrees(q), strict=True)
            for item in ("--posture", f"{name_}={float(angle)!r}")
        ]
        printed = runner.invoke(main, ["torques", path, "--json", *args])
        # A random posture may be flagged (over strength, implausible): exit 1, torques alike.
        assert printed.exit_code in (0, 1), printed.output
        tau_e = np.array([d["external_Nm"] for d in json.loads(printed.stdout)["dofs"]])
        gravity = pin.computeGeneralizedGravity(pm, data, q)
        assert np.max(np.abs(tau_e + gravity)) < 1e-9
