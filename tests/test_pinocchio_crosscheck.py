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

from casadi_posture.cli import main

pin = pytest.importorskip("pinocchio")


def _pinocchio_model(model: dict) -> tuple[object, list[str]]:
    pm = pin.Model()
    pm.gravity.linear = np.array([0.0, 0.0, -model["gravity_m_s2"]])
    joint_id, origin = {None: 0}, {None: np.zeros(3)}
    for dof in model["dofs"]:
        parent = dof.get("parent")
        placement = pin.SE3(np.eye(3), np.array(dof["origin_m"]) - origin[parent])
        joint = pin.JointModelRevoluteUnaligned(np.array(dof["axis"]))
        joint_id[dof["name"]] = pm.addJoint(joint_id[parent], joint, placement, dof["name"])
        origin[dof["name"]] = np.array(dof["origin_m"])
    masses = [(s.get("dof"), s["mass_kg"], s["com_m"]) for s in model["segments"]]
    masses += [(ld["dof"], ld["mass_kg"], ld["point_m"]) for ld in model["loads"]]
    for dof, mass, point in masses:
        if dof is not None:
            lever = np.array(point) - origin[dof]
            pm.appendBodyToJoint(
                joint_id[dof], pin.Inertia(mass, lever, np.zeros((3, 3))), pin.SE3.Identity()
            )
    return pm, [d["name"] for d in model["dofs"]]


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
    pm, dofs = _pinocchio_model(json.loads(described.stdout))
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
        assert printed.exit_code == 0, printed.output
        tau_e = np.array([d["external_Nm"] for d in json.loads(printed.stdout)["dofs"]])
        gravity = pin.computeGeneralizedGravity(pm, data, q)
        assert np.max(np.abs(tau_e + gravity)) < 1e-9
